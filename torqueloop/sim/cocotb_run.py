# SPDX-License-Identifier: MIT
"""Run the step experiment on the cocotb harness (torqueloop/sim/cocotb_board.py)
on Icarus or Verilator, through the project's simrun flow; returns the same
:class:`~torqueloop.sim.experiment.RtlRun` as the native harness."""

from __future__ import annotations

import json
import os
import pickle
from dataclasses import asdict

from torqueloop.sim import experiment
from torqueloop.flow.manifest import REPO_ROOT


def run(cfg: experiment.ExperimentConfig, sim: str) -> experiment.RtlRun:
    from torqueloop.flow.simrun import run as simrun_run
    img = experiment.firmware_image()
    out_dir = REPO_ROOT / "build" / "rtl_loop" / "cocotb"
    out_dir.mkdir(parents=True, exist_ok=True)
    out = out_dir / f"{sim}_{os.getpid()}.pkl"
    # the cocotb module is part of this package: the simulator's Python finds it by name
    simrun_run("rtl_loop", sim, "torqueloop.sim.cocotb_board",
               parameters={"ROM_INIT": f'"{img.rom_hex}"', "RAM_INIT": f'"{img.ram_hex}"'},
               extra_env={"TL_COSIM_CFG": json.dumps(asdict(cfg)), "TL_COSIM_OUT": str(out)})
    with open(out, "rb") as f:
        r = pickle.load(f)
    out.unlink()
    return r
