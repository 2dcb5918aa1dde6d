# SPDX-License-Identifier: MIT
"""The experiment's fast path (torqueloop.sim.experiment.run_fast): CPU
seconds of a case with the plant stepped per control period
(TwoAxisPlant.run_pins, what the study runs) against the same case stepped
edge by edge as the co-simulation does (run_until, ``edges=True``), both in
this run, alternated, the median of N; and how far apart their samples are.
The case: the lab plant (the experiment arm's), P with the Table 1 gains, a
10 s step at 24.4 kHz on both axes (QUICK: 1 s, N = 1), then 50 Hz."""

from __future__ import annotations

import math
import statistics
import time

import numpy as np

from sim_models.variants import PlantSpec
from torqueloop.sim import experiment as ex

COUNT = 2 * math.pi / ex.COUNTS_PER_REV


def _timed(cfg: ex.ExperimentConfig, edges: bool) -> tuple[float, ex.ModelRun]:
    c0 = time.process_time()
    run = ex.run_fast(cfg, edges=edges)
    return time.process_time() - c0, run


def case(plant: str, hz: float, law: str, t_end: float, reps: int) -> tuple[float, float, float]:
    """(median CPU s per period stepping, median edge by edge, ratio of the medians)."""
    cfg = ex.ExperimentConfig(law=law, t_end_s=t_end, plant=PlantSpec(plant), pwm_hz=(hz, hz), progress=False)
    new_s, old_s = [], []
    for _ in range(reps):
        tn, rn = _timed(cfg, False)
        to, ro = _timed(cfg, True)
        new_s.append(tn)
        old_s.append(to)
    a, b = rn.traj, ro.traj
    dq = float(np.abs(a.charge - b.charge).max() / np.abs(b.charge).max())
    new, old = statistics.median(new_s), statistics.median(old_s)
    print(f"| {plant} | {law} | {hz:g} | {t_end:g} | {old:.1f} | {new:.1f} | **{old / new:.2f}** | "
          f"{np.abs(a.pos - b.pos).max() / COUNT:.0f} | {np.abs(a.cmd - b.cmd).max():.0f} | {dq:.1e} |", flush=True)
    return new, old, old / new


def main() -> int:
    from bench import QUICK

    t_end, reps = (1.0, 1) if QUICK else (10.0, 3)
    print(f"CPU seconds per run, median of {reps}; the samples' largest difference (position in counts, "
          f"command in steps, charge relative)")
    print("| plant | law | carrier (Hz) | T (s) | edge by edge | per control period | ratio | "
          "position | command | charge |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    case("lab", 24_400.0, "P", t_end, reps)
    case("paper", 24_400.0, "P", t_end, reps)
    case("lab", 50.0, "P", t_end, 1)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
