# SPDX-License-Identifier: MIT
"""RTL in the loop: simulated clock cycles per second of the full closed loop
(servo firmware on the board image, two axes, plant on the pins, host link),
on the native Verilator harness and on the cocotb harness (Verilator and
Icarus), the projected wall time of the paper's 40 s experiment, where the
time goes (board vs plant vs the rest), and the check that the cocotb and
native harnesses give the same telemetry on the same run.

Figures are per wall second and per CPU second of the process: the machine
is shared, so wall figures depend on the load (printed)."""

from __future__ import annotations

import os
import time
from pathlib import Path

import numpy as np

from torqueloop.sim import cocotb_run, experiment, native
from torqueloop.spec.system import SYSTEM

CLK = SYSTEM.clk_hz


def _line(name: str, r: experiment.RtlRun) -> None:
    b = r.bridge
    print(f"  {name:<22} {r.cycles:>12,} clocks  wall {r.wall_s:7.1f} s  CPU {r.cpu_s:7.1f} s  "
          f"{r.cycles / r.wall_s / 1e6:6.2f} Mclk/wall-s  {r.cycles / r.cpu_s / 1e6:6.2f} Mclk/CPU-s")
    if b.get("board_s"):
        rest = r.wall_s - b["board_s"] - b["plant_s"]
        print(f"  {'':<22} time in board {b['board_s']:.1f} s, plant {b['plant_s']:.1f} s, "
              f"link/recording {rest:.1f} s; {b['segments']} plant segments, {b['rollbacks']} rollbacks, "
              f"{b['edges']} encoder edges, {b['pin_changes']} pin changes")


def _board_alone(n: int = 5_000_000) -> float:
    """Clocks per CPU second of the board image alone (firmware idle loop, no plant, no Python)."""
    img = experiment.firmware_image()
    b = native.NativeBoard.create(img.rom_hex, img.ram_hex)
    b.set_board(0, 1, 0)
    b.run(20, False)
    b.set_board(1, 1, 1)
    c0 = time.process_time()
    b.run(n, False)
    dt = time.process_time() - c0
    b.close()
    return n / dt


def main() -> int:
    print(f"load average {os.getloadavg()[0]:.1f} on {os.cpu_count()} CPUs")
    native.build()
    print(f"native harness, board image alone: {_board_alone() / 1e6:.2f} Mclk/CPU-s (the bound of the native path)")
    cfg = experiment.ExperimentConfig(law="P", t_end_s=1.0, progress=False)
    r = experiment.run_rtl(cfg)
    _line("native Verilator, P 1 s", r)
    per_s = r.cycles / r.wall_s
    print(f"  projected 40 s experiment: {40 * CLK / per_s:.0f} s wall per law at this load "
          f"({40 * CLK / (r.cycles / r.cpu_s):.0f} s of CPU; target 420 s)")
    rep = Path(__file__).resolve().parents[2] / "build" / "report" / "report.json"
    if rep.exists():
        import json
        d = json.loads(rep.read_text())
        for law, v in d.get("arms", {}).get("experiment", {}).items():
            rr = v["run"]
            print(f"  last make run ({d['meta']['T_s']:.0f} s, {law}, experiment arm): {rr['wall_s']:.0f} s wall, "
                  f"{rr['cycles_per_cpu_s'] / 1e6:.2f} Mclk/CPU-s")
    # cocotb harness against native on the same short run (fast link, 1 ms period)
    short = experiment.ExperimentConfig(law="PD", t_end_s=0.02, period_us=1000, baud_div=15, progress=False)
    ref = experiment.run_rtl(short)
    _line("native, short PD", ref)
    for sim in ("verilator", "icarus"):
        run_cfg = short if sim == "verilator" else experiment.ExperimentConfig(
            law="PD", t_end_s=0.002, period_us=1000, baud_div=15, progress=False)
        try:
            c = cocotb_run.run(run_cfg, sim)
        except Exception as e:   # report and go on
            print(f"  cocotb {sim}: failed: {e!r}")
            continue
        _line(f"cocotb {sim}", c)
        n = min(len(c.traj.t), len(ref.traj.t))
        same = all(np.array_equal(getattr(c.traj, k)[:n], getattr(ref.traj, k)[:n])
                   for k in ("pos", "vel", "cmd", "err"))
        print(f"  {'':<22} telemetry of {n} control samples identical to the native harness: {same}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
