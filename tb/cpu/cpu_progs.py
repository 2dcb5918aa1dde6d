# SPDX-License-Identifier: MIT
"""The CPU test programs for the benches in this folder: built by
torqueloop.flow.cpu_progs, run on the ISS oracle (torqueloop.oracles.rv32)."""

from __future__ import annotations

from pathlib import Path

from torqueloop.flow.cpu_progs import BUILD, PROGS, RAM_BASE, RAM_BYTES, build
from torqueloop.oracles.rv32 import IssResult, run_iss as _run_iss

__all__ = ["BUILD", "PROGS", "IssResult", "build", "run_iss"]


def run_iss(elf_path: Path, max_steps: int = 5_000_000) -> IssResult:
    """Run an ELF on the ISS from its entry point until tohost is written."""
    return _run_iss(elf_path, RAM_BASE, RAM_BYTES, max_steps)
