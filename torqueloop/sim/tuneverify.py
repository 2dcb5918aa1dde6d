# SPDX-License-Identifier: MIT
"""``torqueloop tune --verify``: the tuned settings in the closed loop on a
plant, measured with the metrics of report.json's arms.

* ``model``: the fast path (torqueloop.sim.experiment.run_fast): the
  firmware's law in Python (torqueloop/oracles/servo.py, bit for bit the
  C), the PWM block's event model and the plant, with the decoder's edge
  times for the edge-timestamp speed;
* ``rtl``: the board image (Verilator: the SoC running the real servo
  firmware) configured over its link as ``tune --apply`` would, closing the
  loop through its pins with the plant (torqueloop.sim.experiment.run_rtl).

Both move both axes by one screw turn from rest, a step (the paper's
experiment) or, with ``move="trapezoid"``, the firmware's trapezoid profile at
the design's verification VMAX and AMAX (``AxisTune.trapezoid``, from
torqueloop.host.tunedesign.verify_profile),
which the velocity and acceleration feed-forward act on; beside a trapezoid, the
same move without the feed-forward on the fast path, so its benefit shows.  An
axis not tuned runs the board's Table 1 law.  The plant is the plant file the design came from, or
the one ``--verify-plant`` names (in tests: the true plant the
identification did not see).  Beside each tuned axis, on request, the
Table 1 gains of the same law on the same plant on the fast path (the
paper's 25 ms period, its carriers, no dead-zone compensation), so the
tuning's gain shows; the paper's carriers make that run slow (about 4 s of
CPU per simulated second), hence on request.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

from sim_models.variants import PlantSpec
from torqueloop.host.tune import AxisTune
from torqueloop.host.tunedesign import TIGHT_BAND_COUNTS
from torqueloop.sim import experiment
from torqueloop.sim.report import axis_metrics
from torqueloop.spec.metrics import step_metrics

RAD_PER_COUNT = 2 * math.pi / experiment.COUNTS_PER_REV
#: a faster link than the RN-XV's 115 200 baud, so that a frame per control period fits at 1 ms (BAUD_DIV)
FAST_BAUD_DIV = 53


@dataclass(frozen=True)
class Verification:
    path: str                                # "model" or "rtl"
    plant: str
    seconds: float
    tuned: dict[str, dict[str, Any]]         # per tuned axis name: report.json's metrics (+ settling to +-2 counts)
    table1: dict[str, dict[str, Any]]        # the Table 1 gains of the same law, same plant
    faults: list[int]
    wall_s: float
    move: str = "step"                       # "step" or "trapezoid"
    #: a trapezoid: per tuned axis name, the same move without the feed-forward (fast path)
    without_ff: dict[str, dict[str, Any]] = field(default_factory=dict)


def _metrics(run: Any, target_counts: int, a: int, trapezoid: bool = False) -> dict[str, Any]:
    """report.json's metrics of axis ``a``, the settling into +-2 counts, the largest error
    over the record's last tenth and, on a trapezoid, the peak |set-point - position|."""
    tr = run.traj
    follow = {"peak_following_error_counts": float(max(abs(tr.err[:, a])) / RAD_PER_COUNT)} if trapezoid else {}
    out = axis_metrics(tr, target_counts * RAD_PER_COUNT, a)
    tight = step_metrics(tr.t, tr.pos[:, a] / RAD_PER_COUNT, target_counts, band_frac=0.0,
                         band_min=TIGHT_BAND_COUNTS)
    out["settling_time_2_counts_s"] = tight.settling_time_s
    out["max_abs_error_last_10pct_counts"] = float(max(abs(target_counts - tr.pos[-max(1, len(tr.t) // 10):, a]
                                                           / RAD_PER_COUNT)))
    return out | follow


def config(tunes: list[AxisTune], plant: PlantSpec, seconds: float, move: str = "step",
           feedforward: bool = True) -> experiment.ExperimentConfig:
    """The verification's experiment: the tuned settings per axis; a trapezoid at the
    design's verification VMAX and AMAX; ``feedforward`` False: KVFF_Q16 and KAFF_Q16 0."""
    if move not in ("step", "trapezoid"):
        raise ValueError(f"move {move!r}: step or trapezoid")
    period = {round(t.design.period_s * 1e6) for t in tunes}
    if len(period) != 1:
        raise ValueError("the axes were designed at different control periods")
    tuned: list[dict[str, int]] = [{}, {}]
    for t in tunes:
        tuned[t.axis] = t.settings()
        if move == "trapezoid":
            tuned[t.axis] |= {"VMAX": t.trapezoid[0], "AMAX": t.trapezoid[1]}
        if not feedforward:
            tuned[t.axis] |= {"KVFF_Q16": 0, "KAFF_Q16": 0}
    law = "PID" if any(t.design.law == "pid" for t in tunes) else "PD"
    return experiment.ExperimentConfig(law=law, t_end_s=seconds, period_us=period.pop(), plant=plant,
                                       tuned=tuple(tuned), baud_div=FAST_BAUD_DIV, progress=False,
                                       trapezoid=move == "trapezoid")


def verify(tunes: list[AxisTune], plant: PlantSpec, path: str, seconds: float, table1_s: float = 0.0,
           log: Any = print, move: str = "step") -> Verification:
    """Run the tuned move (``move``: "step" or "trapezoid") on ``path`` ("model" or "rtl");
    a trapezoid also without the feed-forward on the fast path; for ``table1_s`` > 0
    seconds, the Table 1 step on the fast path."""
    cfg = config(tunes, plant, seconds, move)
    if path == "rtl":
        run = experiment.run_rtl(cfg, log=log)
        faults = list(run.faults)
    elif path == "model":
        run = experiment.run_fast(cfg)
        faults = []
    else:
        raise ValueError(f"--verify {path!r}: model or rtl")
    target = cfg.target_counts
    trap = move == "trapezoid"
    tuned = {t.name: _metrics(run, target, t.axis, trap) for t in tunes}
    table1 = {}
    if table1_s > 0:
        ref = experiment.run_fast(experiment.ExperimentConfig(law=cfg.law, t_end_s=table1_s, plant=plant,
                                                              progress=False))
        table1 = {t.name: _metrics(ref, target, t.axis) for t in tunes}
    without = {}
    if move == "trapezoid":
        ref = experiment.run_fast(config(tunes, plant, seconds, move, feedforward=False))
        without = {t.name: _metrics(ref, target, t.axis, trap) for t in tunes}
    return Verification(path, plant.label, seconds, tuned, table1, faults, run.wall_s, move, without)
