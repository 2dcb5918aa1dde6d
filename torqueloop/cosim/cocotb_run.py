"""Run the step experiment on the cocotb harness (tb/rtl_loop/cocotb_board.py)
on Icarus or Verilator, through the project's simrun flow; returns the same
:class:`~torqueloop.cosim.experiment.RtlRun` as the native harness."""

from __future__ import annotations

import json
import os
import pickle
import sys
from dataclasses import asdict

from torqueloop.cosim import experiment
from torqueloop.hdl import REPO_ROOT

TB_DIR = REPO_ROOT / "tb" / "rtl_loop"


def run(cfg: experiment.ExperimentConfig, sim: str) -> experiment.RtlRun:
    from torqueloop.simrun import run as simrun_run
    img = experiment.firmware_image()
    out_dir = REPO_ROOT / "build" / "rtl_loop" / "cocotb"
    out_dir.mkdir(parents=True, exist_ok=True)
    out = out_dir / f"{sim}_{os.getpid()}.pkl"
    if str(TB_DIR) not in sys.path:
        sys.path.insert(0, str(TB_DIR))
    os.environ["PYTHONPATH"] = os.pathsep.join([str(TB_DIR), os.environ.get("PYTHONPATH", "")])
    simrun_run("rtl_loop", sim, "cocotb_board",
               parameters={"ROM_INIT": f'"{img.rom_hex}"', "RAM_INIT": f'"{img.ram_hex}"'},
               extra_env={"TL_COSIM_CFG": json.dumps(asdict(cfg)), "TL_COSIM_OUT": str(out),
                          "PYTHONPATH": os.environ["PYTHONPATH"]})
    with open(out, "rb") as f:
        r = pickle.load(f)
    out.unlink()
    return r
