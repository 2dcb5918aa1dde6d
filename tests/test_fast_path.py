# SPDX-License-Identifier: MIT
"""The fast path's plant stepping per control period (TwoAxisPlant.run_pins:
many chunks integrated before their guards are checked in one product, no
encoder edges) against the co-simulation's edge-by-edge stepping
(run_until + TwoAxisPlant.advance) on short runs of the experiment's fast
path, for several carriers and plants.

What may differ, and by how much (docs/plant.md, "The fast path"): on a
plant without winding heating nothing but the order of the sums of the
current integrals, so the samples agree exactly; with heating (``lab``) the
winding's temperature is updated once per control period instead of at
every pin edge of either axis, which moves the plant by a few parts in
1e5 and may move a count across its edge (one count, one command step)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from sim_models.variants import PlantSpec
from torqueloop.sim import experiment as ex

COUNT = 2 * math.pi / ex.COUNTS_PER_REV


def _pair(plant: str, hz: float, law: str, t_end: float):
    cfg = ex.ExperimentConfig(law=law, t_end_s=t_end, plant=PlantSpec(plant), pwm_hz=(hz, hz), progress=False)
    return ex.run_fast(cfg).traj, ex.run_fast(cfg, edges=True).traj


def _rel(a: np.ndarray, b: np.ndarray) -> float:
    return float(np.abs(a - b).max() / max(1e-30, np.abs(b).max()))


@pytest.mark.parametrize("plant,hz,law", [("paper", 24_400.0, "P"), ("paper", 50.0, "PD"),
                                          ("lab-2025", 24_400.0, "PID"), ("lab-2025", 1_700.0, "P")])
def test_per_period_stepping_matches_edges_without_heating(plant, hz, law):
    new, old = _pair(plant, hz, law, 0.1)
    assert np.array_equal(new.pos, old.pos) and np.array_equal(new.cmd, old.cmd)
    assert abs(new.pos[-1, 0]) > 50 * COUNT, "the stage did not move: the comparison shows nothing"
    assert _rel(new.true_pos, old.true_pos) < 1e-9
    assert _rel(new.charge, old.charge) < 1e-9 and _rel(new.i2, old.i2) < 1e-9


@pytest.mark.parametrize("hz", [24_400.0, 1_700.0, 50.0])
def test_per_period_stepping_matches_edges_with_heating(hz):
    new, old = _pair("lab", hz, "P", 0.1)
    assert np.abs(new.pos - old.pos).max() <= 1.5 * COUNT
    assert np.abs(new.cmd - old.cmd).max() <= 2
    assert _rel(new.true_pos, old.true_pos) < 1e-3
    assert _rel(new.charge, old.charge) < 2e-3 and _rel(new.i2, old.i2) < 2e-3
