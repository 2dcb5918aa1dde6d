# SPDX-License-Identifier: MIT
"""Build the CPU test programs (tb/cpu/progs) for the CPU benches, the ISS
tests and the CPI benchmark.

Programs are compiled with Debian's riscv64-unknown-elf-gcc for
rv32im_zicsr / ilp32 (with the register header, firmware/include, on the
include path) and linked with tb/cpu/progs/link.ld (generated,
flow/gen_linker.py) into build/cpu_progs/<tag>/.
"""

from __future__ import annotations

import os
import subprocess
from pathlib import Path

from torqueloop.flow.manifest import REPO_ROOT
from torqueloop.spec import regs

PROGS = REPO_ROOT / "tb" / "cpu" / "progs"
BUILD = REPO_ROOT / "build" / "cpu_progs"
GCC = "riscv64-unknown-elf-gcc"
ARCH = ["-march=rv32im_zicsr", "-mabi=ilp32"]
RAM_BASE = regs.RAM_BASE      # the SoC's memory map, as cpu_sim_top decodes it
RAM_BYTES = regs.RAM_SIZE     # cpu_sim_top's RAM_BYTES default
#: the cores tb/cpu/cpu_sim_top holds: name (run_elf.py --core, the test
#: benches' parameter) -> the harness's parameters
CPU_CORES: dict[str, dict[str, int]] = {"multi": {"PIPELINED": 0}, "pipe": {"PIPELINED": 1}}


def build(name: str, sources: list[Path], tag: str = "", opt: str = "-O2",
          crt0: bool = True) -> Path:
    """Compile and link ``sources`` (C or assembly) into an ELF; return its path."""
    out_dir = BUILD / (tag or "default")
    out_dir.mkdir(parents=True, exist_ok=True)
    elf = out_dir / f"{name}.elf"
    tmp = out_dir / f"{name}.{os.getpid()}.elf"
    srcs = ([PROGS / "crt0.S"] if crt0 else []) + list(sources)
    cmd = [GCC, *ARCH, opt, "-nostdlib", "-ffreestanding", "-static", "-std=c11",
           "-Wall", "-Werror", "-I", str(PROGS), "-I", str(REPO_ROOT / "firmware" / "include"), "-T", str(PROGS / "link.ld"), "-Wl,--no-warn-rwx-segments",
           "-o", str(tmp), *map(str, srcs), "-lgcc"]
    proc = subprocess.run(cmd, capture_output=True, text=True)
    if proc.returncode != 0:
        raise RuntimeError(f"{' '.join(cmd)}\n{proc.stderr}")
    tmp.replace(elf)  # atomic: parallel pytest workers may build the same name
    return elf
