# SPDX-License-Identifier: MIT
"""The identification's fits (torqueloop/host/identfit.py) on the plant.

The plant's stepper (sim_models/stepper.py, the exact flow of every spring,
mode and friction of sim_models/axis.py) is driven the way an open-loop
identification drives a motor: a duty staircase per direction, a coast-down,
a breakaway search from rest.  What the fits make of those traces is held
against the closed forms of sim_models/identifiable.py computed from the
true parameters.  The fits never see the parameters; the plant is the
lab-2025 plant with its friction and rotor inertia scaled by factors the fits do
not know.  This checks the fitting chain on noise-free, averaged traces:
encoder quantisation, PWM and the board's timing are the simulated board's
test (test_identify_simboard)."""

import dataclasses
import math

import numpy as np
import pytest

from sim_models.bridge import BRAKE, COAST
from sim_models.identifiable import identifiable_plant
from sim_models.stepper import TwoAxisPlant
from sim_models.variants import load_variant
from torqueloop.host.identfit import Direction, bisect_threshold, estimates, fit_exponential, fit_line

DT = 0.002
DUTIES = (0.3, 0.5, 0.7)


def test_fit_line_agrees_with_the_textbook_formulas(seed):
    rng = np.random.default_rng(seed)
    x = np.linspace(0, 10, 25)
    y = 3.0 * x - 2.0 + rng.normal(0, 0.5, x.size)
    ln = fit_line(x, y)
    n = x.size
    sxx = np.sum((x - x.mean()) ** 2)
    slope = np.sum((x - x.mean()) * (y - y.mean())) / sxx
    s = math.sqrt(np.sum((y - (slope * x + y.mean() - slope * x.mean())) ** 2) / (n - 2))
    assert ln.slope == pytest.approx(slope, rel=1e-12)
    assert ln.slope_sigma == pytest.approx(s / math.sqrt(sxx), rel=1e-9)
    assert ln.intercept_sigma == pytest.approx(s * math.sqrt(1 / n + x.mean() ** 2 / sxx), rel=1e-9)


def test_fit_exponential_finds_a_known_time_constant(seed):
    rng = np.random.default_rng(seed)
    t = np.arange(0, 1.0, 1e-3)
    w = 500 + (20 - 500) * np.exp(-t / 0.137) + rng.normal(0, 1.0, t.size)
    e = fit_exponential(t, w, 1e-3, 10.0)
    assert e.tau == pytest.approx(0.137, rel=5e-3)
    assert abs(e.tau - 0.137) < 5 * e.tau_sigma
    assert e.final == pytest.approx(500, rel=1e-3)


def _scaled_lab():
    p = load_variant("lab-2025")        # the hard brush drop the closed form inverts exactly
    axes = tuple(a.replace(motor_coulomb_N_m=a.motor_coulomb_N_m * 1.3, motor_static_N_m=a.motor_static_N_m * 1.3,
                           rotor_inertia_kg_m2=a.rotor_inertia_kg_m2 * 0.8) for a in p.axes)
    return dataclasses.replace(p, axes=axes)


def _direction(p, axis: int, sign: int, step_s: float) -> Direction:
    plant = TwoAxisPlant(p, seed=0)
    vs = p.bridge.supply_V
    volts, speeds, taus = [], [], []
    for d in DUTIES:
        v = [0.0, 0.0]
        v[axis] = sign * d * vs
        trace = []
        for _ in range(round(step_s / DT)):
            plant.advance_volts(DT, v)
            trace.append(abs(plant.motor_speed(axis)))
        e = fit_exponential(np.arange(len(trace)) * DT, trace, 1e-3, 10.0)
        volts.append(d * vs)
        speeds.append(e.final)
        taus.append(e.tau)
    coast = []
    pins = [BRAKE, BRAKE]
    pins[axis] = COAST
    while not coast or coast[-1] > 0.2 * speeds[-1]:
        plant.advance(DT, pins)
        coast.append(abs(plant.motor_speed(axis)))
        assert len(coast) < 5.0 / DT, "the coast-down did not slow to 20 % in 5 s"
    w = np.array(coast)
    coast_line = fit_line((w[1:] + w[:-1]) / 2, np.diff(w) / DT)

    def moves(duty: float) -> bool:
        rig = TwoAxisPlant(p, seed=0)
        v = [0.0, 0.0]
        v[axis] = sign * duty * vs
        rig.advance_volts(0.2, v)
        return abs(rig.motor_speed(axis)) > 1.0

    breakaway = bisect_threshold(moves, 0.0, 0.3, 1e-4)
    return Direction(fit_line(volts, speeds), float(np.mean(taus)), float(np.std(taus)), coast_line,
                     100 * breakaway, math.nan)


def test_the_fits_recover_a_plant_they_were_not_told():
    p = _scaled_lab()
    truth = identifiable_plant(p)["x"]
    r = p.axes[0].resistance_ohm + 2 * p.bridge.r_on_ohm
    est = estimates(_direction(p, 0, +1, 1.2), _direction(p, 0, -1, 1.2), r)
    for key, rel in (("speed_gain_rad_per_s_per_v", 0.01), ("time_constant_s", 0.01), ("back_emf_v_s_per_rad", 0.01),
                     ("friction_v_pos", 0.01), ("friction_v_neg", 0.01), ("coulomb_pos_n_m", 0.01),
                     ("coulomb_neg_n_m", 0.01), ("inertia_at_motor_kg_m2", 0.01)):
        assert est[key] == pytest.approx(getattr(truth, key), rel=rel), key
    for key in ("dead_zone_pos_pct", "dead_zone_neg_pct"):
        assert est[key] == pytest.approx(getattr(truth, key), abs=0.05), key
    assert abs(est["viscous_n_m_s_per_rad"]) < 1e-9
    assert est["brush_drop_pos_v"] == pytest.approx(p.axes[0].brush_drop_V, rel=0.02)
