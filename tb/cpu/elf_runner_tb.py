# SPDX-License-Identifier: MIT
"""cocotb side of scripts/run_elf.py: run one ELF on cpu_sim_top.

Inputs and outputs through the environment (set by run_elf.py):
  RUN_ELF             the ELF to run
  RUN_ELF_MAX_CYCLES  cycle limit
  RUN_ELF_RESULT      JSON file written with tohost, cycles, instret
  RUN_ELF_SIGNATURE   optional: file for the begin/end_signature words
"""

from __future__ import annotations

import json
import os
from pathlib import Path

import cocotb

from cpu_tb import CpuTb
from torqueloop.oracles.rv32 import read_elf


@cocotb.test()
async def run_elf(dut):
    elf = read_elf(os.environ["RUN_ELF"])
    tb = CpuTb(dut)
    await tb.load(elf)
    res = await tb.run(int(os.environ["RUN_ELF_MAX_CYCLES"]))
    sig_file = os.environ.get("RUN_ELF_SIGNATURE")
    if sig_file and res.tohost is not None:
        words = await tb.signature(elf)
        Path(sig_file).write_text("".join(f"{w:08x}\n" for w in words))
    Path(os.environ["RUN_ELF_RESULT"]).write_text(
        json.dumps({"tohost": res.tohost, "cycles": res.cycles, "instret": res.instret}))
