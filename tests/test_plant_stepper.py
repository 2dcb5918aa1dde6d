# SPDX-License-Identifier: MIT
"""The fast exact-ZOH stepper against the stiff Radau reference, and its
matrix exponential against scipy's."""

from __future__ import annotations

import random
import time

import numpy as np
import pytest
from scipy.linalg import expm

from sim_models.waveforms import pwm_schedule, run_fast
from sim_models import axis as ax
from sim_models.bridge import Pins
from sim_models.params import load_params
from sim_models.reference import simulate
from sim_models.stepper import FastAxis, TwoAxisPlant, expm_balanced

P = load_params()
FWD, REV = Pins(1, 0, 1, 1), Pins(0, 1, 1, 1)
BRAKE, COAST = Pins(0, 0, 1, 1), Pins(0, 0, 0, 0)
REL_TOL = 1e-6     # the agreement the co-simulation relies on


def _compare(a, schedule, t_end, index, **kw):
    t0 = time.monotonic()
    _, xr, n_ref = simulate(a, P.bridge, schedule, t_end)
    t1 = time.monotonic()
    xf, fa = run_fast(a, P, schedule, t_end, index, **kw)
    t2 = time.monotonic()
    errs = {}
    for k, name in ((ax.PHI_M, "phi_m"), (ax.PHI_S, "phi_s"), (ax.CHI_L, "chi_l"), (ax.I_, "i")):
        scale = np.abs(xr[:, k]).max()
        errs[name] = float(np.abs(xf[:, k] - xr[:, k]).max() / scale) if scale > 0 else 0.0
    errs["chi_l_abs_m"] = float(np.abs(xf[:, ax.CHI_L] - xr[:, ax.CHI_L]).max())
    print(f"reference {t1 - t0:.2f} s ({n_ref} switches), fast {t2 - t1:.3f} s "
          f"({fa.events} switches), relative errors {errs}")
    return errs, n_ref, fa.events


def test_balanced_expm_matches_scipy():
    fa = FastAxis(P.axes[0], P, 0)
    fa.set_pins(FWD)
    s = fa._system()
    for tau in (1e-7, 1e-5, 2.5e-4, 1e-3, 5e-3):
        ref = expm(s.m * tau)
        got = expm_balanced(s.mb, s.bal, tau)
        assert np.abs(got - ref).max() <= 1e-9 * np.abs(ref).max()


def test_fast_matches_reference_brake_pwm_axis1():
    """450 Hz slow-decay PWM with a duty that changes every period."""
    seed = random.randrange(2**31)
    print(f"seed {seed}")
    rng = random.Random(seed)
    duties = [rng.uniform(0.2, 0.95) for _ in range(30)]
    sched = pwm_schedule(0.03, 450.0, lambda k: duties[k], lambda k: FWD, lambda k: BRAKE)
    errs, _, _ = _compare(P.axes[0], sched, 0.03, 0)
    assert max(errs["phi_m"], errs["phi_s"], errs["chi_l"], errs["i"]) < REL_TOL


def test_fast_matches_reference_coast_pwm_axis2_discontinuous_current():
    """200 Hz fast-decay PWM on the vertical axis: the current reaches zero
    and stays there every period (an electrical mode switch each time)."""
    sched = pwm_schedule(0.05, 200.0, lambda k: 0.3, lambda k: FWD, lambda k: COAST)
    errs, n_ref, n_fast = _compare(P.axes[1], sched, 0.05, 1)
    assert n_ref == n_fast >= 10
    assert max(errs["phi_m"], errs["phi_s"], errs["chi_l"], errs["i"]) < REL_TOL


def test_fast_matches_reference_through_stick_slip():
    """Direction reversals every two periods make the light vertical table
    stick and slip repeatedly."""
    a = P.axes[1].replace(table_coulomb_N=0.6)
    sched = pwm_schedule(0.04, 450.0, lambda k: 0.9, lambda k: FWD if (k // 2) % 2 == 0 else REV,
                         lambda k: BRAKE)
    errs, n_ref, n_fast = _compare(a, sched, 0.04, 1)
    assert n_ref >= 4 and n_fast == n_ref
    assert max(errs["phi_m"], errs["phi_s"], errs["chi_l"], errs["i"]) < REL_TOL


def test_fast_matches_reference_through_backlash_and_clearance():
    """Gear backlash, nut clearance and table friction all switching, with
    direction reversals and alternating brake/coast off-phases.  The
    drivetrain after the gear is softened (coupling, screw, nut, bearing) so
    that the reference resolves the contact bounces in a few seconds; the
    Table 2 stiffness with backlash is compared in the benchmark."""
    a = P.axes[0].replace(gear_backlash_rad=5e-4, nut_clearance_m=2e-7, table_coulomb_N=0.05,
                          coupling_stiffness_N_m_per_rad=50.0, screw_torsion_N_m_per_rad=500.0,
                          nut_stiffness_N_per_m=2e5, screw_axial_N_per_m=2e5)
    sched = pwm_schedule(0.012, 450.0, lambda k: 0.7 if k % 4 < 2 else 0.4,
                         lambda k: FWD if k % 4 < 2 else REV,
                         lambda k: BRAKE if k % 2 else COAST)
    errs, n_ref, n_fast = _compare(a, sched, 0.012, 0)
    assert n_ref >= 8 and n_fast == n_ref
    # the table moves only ~0.1 um here: its error is bounded absolutely
    assert max(errs["phi_m"], errs["phi_s"], errs["i"]) < REL_TOL
    assert errs["chi_l_abs_m"] < 1e-12


def test_two_axis_api_and_timing_of_edges():
    plant = TwoAxisPlant(seed=1)
    edges = plant.advance(0.05, (FWD, REV))
    assert edges, "both motors turn within 50 ms"
    assert all(0.0 < e.t <= 0.05 for e in edges)
    assert [e.t for e in edges] == sorted(e.t for e in edges)
    assert {e.axis for e in edges} == {0, 1}
    assert plant.count(0) > 0 > plant.count(1)
    assert plant.motor_speed(0) > 0 > plant.motor_speed(1)
    r_is, l_is = plant.is_currents(0)
    assert r_is == pytest.approx(plant.current(0) / P.bridge.k_ilis) and l_is == 0.0
    assert plant.table_mm(0) == pytest.approx(1e3 * plant.state(0)[ax.CHI_L])


def test_current_integrals_are_exact_through_events() -> None:
    """energy=True: the integrals of i and i^2 (charge, copper loss) through a
    lab-plant PWM run with stick-slip and discontinuous-conduction events,
    taken in whole PWM phases, equal a 0.1 us trapezoid of the same run."""
    from sim_models.variants import load_variant

    p = load_variant("lab-2025")
    coarse = FastAxis(p.axes[0], p, 0, energy=True)
    fine = FastAxis(p.axes[0], p, 0, energy=True)
    ts, iv, t = [0.0], [0.0], 0.0
    for k in range(12):
        on = 0.2 + 0.03 * (k % 5)
        for pins, dur in ((FWD, on / 2000), (BRAKE, (1 - on) / 2000)):
            coarse.set_pins(pins)
            coarse.advance(dur, [])
            fine.set_pins(pins)
            for _ in range(int(round(dur / 1e-7))):
                fine.advance(1e-7, [])
                t += 1e-7
                ts.append(t)
                iv.append(fine.x[ax.I_])
    assert coarse.events > 10
    assert coarse.q_i == pytest.approx(fine.q_i, rel=1e-9)
    assert coarse.q_i2 == pytest.approx(fine.q_i2, rel=1e-8)
    assert coarse.q_i == pytest.approx(np.trapezoid(iv, ts), rel=1e-6)
    assert coarse.q_i2 == pytest.approx(np.trapezoid(np.square(iv), ts), rel=1e-5)


def test_tick_integrals_match_scipy_van_loan():
    """The current integrals over one tick (Van Loan's block exponential by
    expm_balanced) against scipy's expm of the same blocks."""
    from sim_models.variants import PlantSpec
    lab = PlantSpec("lab").params()
    fa = FastAxis(lab.axes[1], lab, 1, energy=True)
    fa.set_pins(FWD)
    s = fa._system()
    r, g = fa._tick_integrals(s)
    n, tau, mb, bal = len(s.mb), fa.tick, s.mb, s.bal
    cb = np.zeros(n)
    cb[ax.I_] = bal[ax.I_]
    a = np.zeros((2 * n, 2 * n))
    a[:n, :n], a[:n, n:] = mb, np.eye(n)
    v = np.zeros((2 * n, 2 * n))
    v[:n, :n], v[:n, n:], v[n:, n:] = -mb.T, np.outer(cb, cb), mb
    e = expm(v * tau)
    r_ref = (cb @ expm(a * tau)[:n, n:]) / bal
    g_ref = (e[n:, n:].T @ e[:n, n:]) / bal[:, None] / bal[None, :]
    assert np.abs(r - r_ref).max() <= 1e-12 * np.abs(r_ref).max()
    assert np.abs(g - g_ref).max() <= 1e-12 * np.abs(g_ref).max()
