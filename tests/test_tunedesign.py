# SPDX-License-Identifier: MIT
"""The tuning design (torqueloop/host/tunedesign.py) against closed forms.

The step metrics it predicts are the design model's; whether the board image
in the loop meets them is tune --verify's measurement, not this file's."""

import cmath
import math

import numpy as np
import pytest

from sim_models.identifiable import identifiable_plant
from sim_models.variants import load_variant
from torqueloop.host.tunedesign import AxisModel, Wish, closed_loop, design, discrete_plant, predict, zeta_for_overshoot


def _lab(axis: str) -> AxisModel:
    return AxisModel.from_identified(identifiable_plant(load_variant("lab"))[axis].as_dict())


@pytest.mark.parametrize("pct", [2.0, 5.0, 10.0])
def test_damping_for_an_overshoot_is_the_second_order_closed_form(pct):
    z = zeta_for_overshoot(pct)
    if z > 0.7:
        assert 100 * math.exp(-math.pi * z / math.sqrt(1 - z * z)) == pytest.approx(pct, rel=1e-9)


@pytest.mark.parametrize("law", ["pd", "pid"])
def test_the_discrete_poles_are_where_the_continuous_design_put_them(law):
    """At a control period far below the loop's time scales the exact ZOH loop's
    poles are exp(s T) of the continuous poles the design placed."""
    m = _lab("x")
    t = 1e-5
    d = design(m, Wish(law=law, period_s=t, settling_s=0.5, tolerance_counts=1e9))
    wn, z = d.wn, d.zeta
    want = [cmath.exp(t * wn * (-z + 1j * math.sqrt(1 - z * z))), cmath.exp(t * wn * (-z - 1j * math.sqrt(1 - z * z)))]
    if law == "pid":
        want.append(cmath.exp(-t * wn))
    got = sorted(d.poles_z, key=lambda p: (p.real, p.imag))
    for w in sorted(want, key=lambda p: (p.real, p.imag)):
        assert min(abs(g - w) for g in got) < 1e-4 * t * wn * 10


def test_the_gain_margin_is_where_the_loop_goes_unstable():
    m = _lab("z")
    w = Wish(law="pd", period_s=5e-3)
    d = design(m, w)
    ad, bd = discrete_plant(m.kc(d.pw0), m.tau, w.period_s)
    g = 10 ** (d.gain_margin_db / 20)
    def radius(f):
        return max(abs(np.linalg.eigvals(closed_loop(ad, bd, f * d.kp, f * d.kd, f * d.ki, w.period_s))))
    assert radius(g * 0.99) < 1.0 <= radius(g * 1.01)
    assert d.phase_margin_deg > 45


def test_a_pd_sized_for_stiction_holds_within_its_tolerance():
    m = _lab("x")
    d = design(m, Wish(law="pd", period_s=1e-3, tolerance_counts=2.0))
    assert d.stick_band_counts <= 2.0 + 1e-9
    _, _, met = predict(m, d, 8400, 3.0)
    assert met.settling_time_s is not None
    assert abs(met.steady_state_error) <= 2.0
    assert met.overshoot_pct <= 2.0


def test_a_period_too_long_for_the_wish_is_said_not_hidden():
    d = design(_lab("x"), Wish(law="pd", period_s=25e-3, settling_s=0.2))
    assert any("capped" in n for n in d.notes)
    assert d.wn * 25e-3 <= 0.15 + 1e-12


def test_the_compensation_over_drives_neither_direction():
    """PW0 at the smaller direction's sliding friction, rounded down; a PD's FC
    lifts each direction to its own (within a step); a PID's integral holds the
    difference (FC 0) and its hunting guard is the encoder's one count."""
    m = AxisModel(speed_gain=100.0, tau=0.1, friction_v=(1.0, 0.83), breakaway_pct=(9.0, 7.5))
    volts_per_tick = m.supply_v / m.full
    pw0 = m.pw0()
    assert pw0 * volts_per_tick <= 0.83 < (pw0 + 1) * volts_per_tick    # rounded down: 70, not 71
    fc = m.fc(pw0, "pd")
    step_v = volts_per_tick * (m.full - pw0) / m.full
    for f, vf in zip(fc, m.friction_v):
        assert abs((pw0 + f * (m.full - pw0) / m.full) * volts_per_tick - vf) <= step_v / 2 + 1e-12
    assert fc[0] > fc[1]
    assert m.fc(pw0, "pid") == (0, 0)
    pid = design(m, Wish(law="pid"))
    assert pid.fc == (0, 0) and pid.compensation()["IZONE_Q16"] == 65536
    assert design(m, Wish(law="pid", tolerance_counts=0.5)).izone_counts == 0
    pd = design(m, Wish(law="pd"))
    assert pd.fc == fc and pd.compensation()["IZONE_Q16"] == 0
