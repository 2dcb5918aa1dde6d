# SPDX-License-Identifier: MIT
"""The stability study (torqueloop/study/stability.py): the protocols' sweep
orders, the verdict, and the one thing that lets the order matter on the
simulated bench - a reading starts at the winding temperature the last one
left."""

from __future__ import annotations

import pytest

from sim_models.variants import PlantSpec
from torqueloop.spec.pwm import divider_for
from torqueloop.study.stability import CarriedBench, Protocol, verdict


def test_orders_cover_the_same_carriers() -> None:
    f = (50.0, 235.0, 1111.0, 24_400.0)
    assert Protocol(0.3, "up").sequence(f) == sorted(f)
    assert Protocol(0.3, "down").sequence(f) == sorted(f, reverse=True)
    s = Protocol(0.3, "shuffled", seed=3).sequence(f)
    assert sorted(s) == sorted(f) and s == Protocol(1.0, "shuffled", seed=3).sequence(f)
    with pytest.raises(ValueError):
        Protocol(0.3, "sideways")
    with pytest.raises(ValueError):
        Protocol(-1.0, "up")


def test_verdict_names_a_carrier_only_where_every_protocol_agrees() -> None:
    rows = [{"axis": "x", "settle_s": s, "freq_hz": f} for s, f in ((0.3, 1000.0), (1.0, 1100.0), ("converged", 1200.0))]
    rows += [{"axis": "z", "settle_s": s, "freq_hz": f} for s, f in ((0.3, 200.0), (1.0, 600.0), ("converged", None))]
    rows += [{"axis": "y", "settle_s": s, "freq_hz": 235.0, "kind": "nearest"} for s in (0.3, 1.0)]
    v = verdict(rows)
    assert v["x"]["stable"] and v["x"]["min_hz"] == 1000.0 and v["x"]["max_hz"] == 1200.0
    assert not v["z"]["stable"] and v["z"]["chosen"] == 2
    assert not v["y"]["stable"], "the grid's edge where nothing crossed is no choice"


def test_a_reading_starts_at_the_temperature_the_last_one_left() -> None:
    """Two stall readings in a row (no pause): the second starts warm, its
    winding resistance is higher and it reads less torque."""
    b = CarriedBench(PlantSpec("lab"), "x", Protocol(0.3, "up", pause_s=0.0))
    n = divider_for(24_400.0)
    first, second = b.reading(n, 1023), b.reading(n, 1023)
    assert first["theta_start_K"] == 0.0 and second["theta_start_K"] == pytest.approx(first["theta_end_K"])
    assert first["theta_end_K"] > 2.0
    assert second["torque_nm"] < first["torque_nm"] * (1 - 0.5 * 0.00393 * first["theta_end_K"])
