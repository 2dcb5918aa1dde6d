# SPDX-License-Identifier: MIT
"""The ELF runner's contract (scripts/run_elf.py): exit codes, counts, signature, memory map."""

from __future__ import annotations

import re
import subprocess
import sys

import pytest

from cpu_progs import PROGS, build, run_iss
from torqueloop.flow.manifest import REPO_ROOT
from torqueloop.flow.simrun import sims_for

RUN_ELF = REPO_ROOT / "scripts" / "run_elf.py"
SIMS = sims_for("cpu_sim_top", langs=("verilog",))


def run_elf(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, str(RUN_ELF), *args], capture_output=True, text=True, timeout=600)


def test_run_elf_memory_map():
    out = run_elf("--memory-map")
    assert out.returncode == 0
    m = re.fullmatch(r"ram_base=0x([0-9a-f]{8}) ram_size=0x([0-9a-f]+)\n", out.stdout)
    assert m and int(m.group(1), 16) == 0x8000_0000 and int(m.group(2), 16) >= 64 * 1024


# One test per simulator: the runs share one simulator build (no parallel builds of it).
@pytest.mark.parametrize("sim", SIMS)
def test_run_elf_contract(sim, tmp_path):
    elf = build("traps", [PROGS / "traps.S"], tag=f"run_elf_{sim}", crt0=False)
    sig = tmp_path / "sig.txt"
    out = run_elf(str(elf), "--sim", sim, "--signature", str(sig))
    assert out.returncode == 0, out.stdout + out.stderr
    ref = run_iss(elf)
    lines = sig.read_text().splitlines()
    assert all(re.fullmatch(r"[0-9a-f]{8}", l) for l in lines)
    assert [int(l, 16) for l in lines] == ref.signature
    m = re.search(r"cycles=(\d+) instructions=(\d+)", out.stdout)
    assert m and int(m.group(2)) == ref.instructions + 2  # + the boot stub's lui/jalr

    fail = build("fail3", [PROGS / "fail3.c"], tag=f"run_elf_{sim}")
    out = run_elf(str(fail), "--sim", sim)
    assert out.returncode == 1 and "test 3" in out.stdout, out.stdout + out.stderr
    hang = build("hang", [PROGS / "hang.c"], tag=f"run_elf_{sim}")
    out = run_elf(str(hang), "--sim", sim, "--max-cycles", "3000")
    assert out.returncode == 2 and "3000 cycles" in out.stdout, out.stdout + out.stderr
