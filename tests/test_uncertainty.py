# SPDX-License-Identifier: MIT
"""The parameter-uncertainty Monte Carlo (torqueloop/study/uncertainty.py):
draws stay within their stated ranges and repeat with their seed, and a
draw's plant is the lab plant with exactly those values."""

from __future__ import annotations

import random

import pytest

from sim_models.variants import PlantSpec
from torqueloop.study.uncertainty import RANGES, draw, interval, params_of


def test_draws_stay_in_their_ranges_and_repeat_with_the_seed() -> None:
    rng = random.Random(7)
    ds = [draw(rng) for _ in range(200)]
    for k, (lo, hi, _, _) in RANGES.items():
        v = [d[k] for d in ds]
        assert lo <= min(v) and max(v) <= hi and max(v) - min(v) > 0.8 * (hi - lo)
    assert ds[:3] == [draw(r) for r in [random.Random(7)] for _ in range(3)]


def test_a_draws_plant_has_its_values() -> None:
    """Resistance and inertia scaled by the draw's factors; friction at its
    fraction of the nominal stall torque (the factors apply after it)."""
    base = PlantSpec("lab").params()
    d = {"coulomb_frac": 0.04, "brush_volts": 0.8, "gear_back": 0.9, "inertia_factor": 1.2, "r_factor": 1.1}
    p = params_of(PlantSpec("lab"), d)
    for a, b in zip(p.axes, base.axes):
        assert a.resistance_ohm == pytest.approx(1.1 * b.resistance_ohm)
        assert a.rotor_inertia_kg_m2 == pytest.approx(1.2 * b.rotor_inertia_kg_m2)
        assert a.motor_coulomb_N_m / b.motor_coulomb_N_m == pytest.approx(0.04 / 0.03, rel=0.02)


def test_interval_names_percentiles_only_with_enough_draws() -> None:
    assert "p10" not in interval([1.0, 2.0, 3.0]) and interval([1.0, 2.0, 3.0])["median"] == 2.0
    assert interval([float(x) for x in range(10)])["p90"] == pytest.approx(8.1)
