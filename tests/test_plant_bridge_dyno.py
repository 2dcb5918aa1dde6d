# SPDX-License-Identifier: MIT
"""BTS7960 bridge truth table, IS pin, and the dynamometer bench model."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from sim_models.bridge import BRAKE, COAST, Pins, armature_voltages, is_currents
from sim_models.dyno import DynamometerBench, DynoConfig
from sim_models.params import load_params

P = load_params()
B = P.bridge
VS, VF = B.supply_V, B.diode_V


@pytest.mark.parametrize("pins, expect", [
    (Pins(1, 0, 1, 1), (VS, VS)),                   # forward
    (Pins(0, 1, 1, 1), (-VS, -VS)),                 # reverse
    (BRAKE, (0.0, 0.0)),                            # both low sides: brake
    (Pins(1, 1, 1, 1), (0.0, 0.0)),                 # both high sides: brake to supply
    (COAST, (-(VS + 2 * VF), VS + 2 * VF)),         # both off: diodes oppose the current
    (Pins(1, 0, 0, 0), (-(VS + 2 * VF), VS + 2 * VF)),  # PWM ANDed with enable
    (Pins(0, 0, 1, 0), (-(VS + VF), VF)),           # one side low, other floating
])
def test_armature_voltage_truth_table(pins, expect):
    assert armature_voltages(pins, B) == pytest.approx(expect)


def test_is_pin_reports_high_side_current_over_8500():
    assert is_currents(Pins(1, 0, 1, 1), 2.0, B) == pytest.approx((2.0 / 8500, 0.0))
    assert is_currents(Pins(0, 1, 1, 1), -1.7, B) == pytest.approx((0.0, 1.7 / 8500))
    assert is_currents(BRAKE, 2.0, B) == (0.0, 0.0)


def _mean_current_by_ode(axis, freq, duty, drive):
    """Independent oracle: integrate L di/dt = E - R i over many periods
    with solve_ivp (event at i = 0 while the bridge floats) and average."""
    dyn = DynamometerBench(axis, B)
    r, l_ = dyn.r_tot, axis.inductance_H
    per = 1.0 / freq
    on = duty * per + B.turn_off_delay_s - B.turn_on_delay_s
    i, t_all, i_all = 0.0, [], []
    for k in range(30):
        for t0, t1, is_on in ((k * per, k * per + on, True), (k * per + on, (k + 1) * per, False)):
            if drive == "brake":
                e_of = (lambda _i: VS) if is_on else (lambda _i: 0.0)
            else:
                e_of = (lambda _i: VS) if is_on else (lambda _i: -(VS + 2 * VF) if _i > 0 else 0.0)
            def f(_t, y):
                if not is_on and drive == "coast" and y[0] <= 0:
                    return [0.0]
                return [(e_of(y[0]) - r * y[0]) / l_]
            def hit(_t, y):
                return y[0]
            hit.terminal = True
            hit.direction = -1
            sol = solve_ivp(f, (t0, t1), [i], rtol=1e-11, atol=1e-13, dense_output=True,
                            events=hit if (drive == "coast" and not is_on) else None, max_step=per / 50)
            tt = np.linspace(t0, t1, 400)
            ii = np.clip(sol.sol(np.minimum(tt, sol.t[-1])).ravel(), 0 if drive == "coast" else -1e9, None)
            if sol.status == 1:
                ii[tt > sol.t[-1]] = 0.0
                i = 0.0
            else:
                i = float(sol.y[0, -1])
            if k >= 20:
                t_all.append(tt)
                i_all.append(ii)
    return float(sum(np.trapezoid(y, t) for y, t in zip(i_all, t_all)) / (10 * per))


@pytest.mark.parametrize("drive", ["brake", "coast"])
@pytest.mark.parametrize("freq", [50.0, 450.0])
def test_dyno_mean_current_matches_ode_oracle(drive, freq):
    a = P.axes[0]
    got = DynamometerBench(a, B).measure(freq, 0.5, drive=drive).current_A
    want = _mean_current_by_ode(a, freq, 0.5, drive)
    assert got == pytest.approx(want, rel=2e-4)


def test_brake_mode_torque_is_linear_in_duty_and_nearly_frequency_independent():
    a = P.axes[0]
    dyn = DynamometerBench(a, B)
    tau_max = dyn.tau_max()
    assert tau_max == pytest.approx(a.km_N_m_per_A * VS / dyn.r_tot, rel=1e-9)
    # 0.7 us pulse shortening: a duty loss of 0.7 us * f
    for f in (50.0, 200.0, 450.0, 500.0):
        m = dyn.measure(f, 0.5)
        assert m.torque_N_m / tau_max == pytest.approx(0.5 - 0.7e-6 * f, abs=1e-9)
    duties = np.linspace(0.05, 0.95, 19)
    tq = np.array([dyn.measure(450.0, d).torque_N_m for d in duties])
    fit = np.polyfit(duties, tq, 1)
    assert np.abs(np.polyval(fit, duties) - tq).max() < 1e-9 * tau_max


def test_coast_mode_torque_falls_with_frequency():
    dyn = DynamometerBench(P.axes[0], B, DynoConfig(drive="coast"))
    t = [dyn.measure(f, 0.5).torque_N_m for f in (50.0, 200.0, 450.0)]
    assert t[0] > t[1] > t[2]
    assert t[2] < 0.45 * dyn.tau_max()


def test_force_is_torque_over_radius_and_is_pin_tracks_current():
    cfg = DynoConfig(wheel_radius_m=0.05, rope_angle_deg=60.0)
    m = DynamometerBench(P.axes[1], B, cfg).measure(200.0, 0.3)
    assert m.force_N == pytest.approx(m.torque_N_m / (0.05 * np.sin(np.radians(60))))
    # brake mode: the high side carries the current only during the on-phase
    assert 0 < m.is_pin_A < m.current_A / B.k_ilis
