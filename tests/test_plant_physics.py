# SPDX-License-Identifier: MIT
"""Physical invariants of the plant model (sim_models.axis)."""

from __future__ import annotations

import math
import random

import numpy as np
import pytest

from sim_models import axis as ax
from sim_models.bridge import BRAKE, Pins, armature_voltages
from sim_models.params import load_params
from sim_models.stepper import FastAxis

P = load_params()
FWD = Pins(1, 0, 1, 1)


def test_table2_interpretation_gives_documented_motor_figures():
    """docs/plant.md quotes these; the paper's tau_max/2 = 1.2 N m (motor 1)."""
    a1, a2 = P.axes
    assert a1.stall_torque_out_N_m(12.0) == pytest.approx(2.258, abs=1e-3)
    assert a2.stall_torque_out_N_m(12.0) == pytest.approx(2.899, abs=1e-3)
    assert a1.no_load_motor_rad_s(12.0) == pytest.approx(2298.9, abs=0.1)
    assert a1.electrical_tau_s == pytest.approx(2.0e-4, rel=1e-3)
    assert a2.electrical_tau_s == pytest.approx(2.0e-4, rel=1e-3)


@pytest.mark.parametrize("index", [0, 1])
def test_static_deflection_and_stall_current(index):
    """Table held by friction, full forward voltage: at equilibrium the
    current is V/R (stall) and the motor has turned by the output torque
    over the series stiffness of gear, coupling, screw and nut/bearing."""
    a = P.axes[index].replace(gear_efficiency=1.0, table_coulomb_N=1e9, gravity_m_s2=0.0)
    c = ax.AxisConsts.build(a, P.bridge)
    e_pos, e_neg = armature_voltages(FWD, P.bridge)
    amat, b = ax.affine(c, ax.Mode(1, 1, 1, 0), e_pos, e_neg)
    keep = [k for k in range(ax.N_STATE) if k not in (ax.CHI_L, ax.V_L)]
    x = np.zeros(ax.N_STATE)
    x[keep] = np.linalg.solve(amat[np.ix_(keep, keep)], -b[keep])
    i_stall = P.bridge.supply_V / c.R
    assert x[ax.I_] == pytest.approx(i_stall, rel=1e-12)
    torque_out = a.km_N_m_per_A * i_stall
    assert x[ax.PHI_M] / a.gear_ratio == pytest.approx(
        torque_out / a.series_stiffness_out_N_m_per_rad, rel=1e-9)
    assert np.abs(x[ax.W_M:]).max() < 1e-12


def test_no_load_speed_is_v_over_ke():
    a = P.axes[0].replace(table_coulomb_N=0.0)
    p = P.__class__(axes=(a, P.axes[1]), bridge=P.bridge.__class__(r_on_ohm=0.0), encoder=P.encoder)
    fa = FastAxis(a, p, 0)
    fa.set_pins(FWD)
    fa.advance(5.0, [])          # > 15 mechanical time constants (0.26 s)
    assert fa.x[ax.W_M] == pytest.approx(12.0 / a.ke_V_s_per_rad, rel=1e-6)
    assert fa.x[ax.I_] == pytest.approx(0.0, abs=1e-6)


def _energy(a, x: np.ndarray) -> float:
    """Total energy written from the equations (eq 8, 9 and L i^2 / 2)."""
    g, rn = a.gear_ratio, a.screw_m_per_rad
    ic3 = a.coupling_inertia_kg_m2 / 3
    inertia = [a.rotor_inertia_kg_m2, a.rotor_inertia_kg_m2 / (a.gear_efficiency * g) ** 2 + ic3,
               ic3, ic3 + a.screw_inertia_kg_m2, a.screw_mass_kg + a.table_mass_kg, a.table_mass_kg]
    kin = 0.5 * sum(j * w * w for j, w in zip(inertia, x[7:13]))
    pot = 0.5 * (a.gear_stiffness_N_m_per_rad * (x[1] / g - x[2]) ** 2
                 + a.coupling_stiffness_N_m_per_rad * (x[2] - x[3]) ** 2
                 + a.screw_torsion_N_m_per_rad * (x[3] - x[4]) ** 2
                 + a.nut_stiffness_N_per_m * (x[6] - rn * x[4] - x[5]) ** 2
                 + a.screw_axial_N_per_m * x[5] ** 2)
    pot += a.table_mass_kg * a.gravity_m_s2 * x[6]
    return kin + pot + 0.5 * a.inductance_H * x[0] ** 2


def test_energy_is_conserved_without_damping_and_friction():
    """No damping, no friction, no resistance, k_t = k_e and an ideal gear:
    the shorted motor exchanges energy with the mechanics without loss."""
    seed = random.randrange(2**31)
    print(f"seed {seed}")
    rng = np.random.default_rng(seed)
    a0 = P.axes[1]   # the vertical axis: gravity potential included
    a = a0.replace(gear_efficiency=1.0, gear_damping_N_m_s_per_rad=0.0,
                   nut_damping_N_s_per_m=0.0, screw_axial_damping_N_s_per_m=0.0,
                   table_coulomb_N=0.0, resistance_ohm=0.0,
                   km_N_m_per_A=a0.ke_V_s_per_rad * a0.gear_ratio)
    p = P.__class__(axes=(a, a), bridge=P.bridge.__class__(r_on_ohm=0.0), encoder=P.encoder)
    fa = FastAxis(a, p, 0)
    x0 = np.zeros(ax.N_STATE)
    x0[ax.I_] = rng.normal(0, 1.0)
    x0[7:13] = rng.normal(0, 1, 6) * [100, 0.5, 0.5, 0.5, 1e-3, 1e-3]
    x0[ax.CHI_S] = 1e-6 * rng.normal()
    fa.set_pins(BRAKE)
    fa.set_state(x0)
    e0 = _energy(a, fa.x)
    worst = 0.0
    for _ in range(200):
        fa.advance(1e-3, [])
        worst = max(worst, abs(_energy(a, fa.x) - e0) / e0)
    assert worst < 1e-8, worst


def test_natural_frequency_of_reduced_two_inertia_case():
    """Everything after the gear made far stiffer (torsion 1e5x, axial 1e9x
    since it acts through R_n^2 = 4e-7 m^2/rad^2): the lowest
    vibration mode is the motor rotor against the output-side inertia
    (screw, coupling, table reflected through R_n) on the mesh stiffness:
    w^2 = k_g (1 / (G^2 J_m) + 1 / J_out)."""
    a0 = P.axes[0]
    s = 1e5
    a = a0.replace(gear_efficiency=1.0, gear_damping_N_m_s_per_rad=0.0,
                   nut_damping_N_s_per_m=0.0, screw_axial_damping_N_s_per_m=0.0,
                   table_coulomb_N=0.0,
                   coupling_stiffness_N_m_per_rad=a0.coupling_stiffness_N_m_per_rad * s,
                   screw_torsion_N_m_per_rad=a0.screw_torsion_N_m_per_rad * s,
                   nut_stiffness_N_per_m=a0.nut_stiffness_N_per_m * s * 1e4,
                   screw_axial_N_per_m=a0.screw_axial_N_per_m * s * 1e4)
    c = ax.AxisConsts.build(a, P.bridge)
    amat, _ = ax.affine(c, ax.Mode(0, 1, 1, 1), 0.0, 0.0)   # current held at 0
    lam = np.linalg.eigvals(amat[1:, 1:])
    w = np.sort(np.abs(lam.imag[lam.imag > 1.0]))   # oscillatory modes only
    g = a.gear_ratio
    j_out = c.inertia[1] + c.inertia[2] + c.inertia[3] + a.table_mass_kg * a.screw_m_per_rad**2
    w_hand = math.sqrt(a.gear_stiffness_N_m_per_rad * (1 / (g * g * a.rotor_inertia_kg_m2) + 1 / j_out))
    assert w[0] == pytest.approx(w_hand, rel=1e-3)


def test_gravity_pulls_the_unpowered_vertical_axis_down():
    p = load_params()
    fa = FastAxis(p.axes[1], p, 1)
    fa.set_pins(BRAKE)
    fa.advance(0.5, [])
    assert fa.x[ax.CHI_L] < 0 and fa.x[ax.V_L] <= 0


@pytest.mark.parametrize("beyond, sticks", [(5e-14, True), (1e-6, False)])
def test_a_table_at_the_edge_of_its_friction_sticks_instead_of_chattering(beyond, sticks):
    """A sliding table whose velocity reaches zero while the force on it is
    its Coulomb force plus rounding (5e-14 N, met on axis z under PD at
    50 Hz) sticks, and the stuck mode's guards hold at that state; it used to
    slide on with no acceleration and re-fire the same guard without end
    (the stepper's "Zeno?" error stopped make run).  Clearly beyond the
    friction (1e-6 N) it slides on."""
    from sim_models.variants import load_variant

    p = load_variant("lab")
    c = ax.AxisConsts.build(p.axes[1], p.bridge)
    mode = ax.Mode(se=0, cg=1, cn=1, sl=-1, sm=0, gd=1)
    x = np.zeros(ax.N_STATE)
    # the table hold force is affine in the table position: place it at -(fc + beyond)
    h0 = ax.table_hold_force(c, x, mode)
    x1 = x.copy()
    x1[ax.CHI_L] = 1e-6
    slope = (ax.table_hold_force(c, x1, mode) - h0) / 1e-6
    x[ax.CHI_L] = (-(c.fc + beyond) - h0) / slope
    assert ax.table_hold_force(c, x, mode) == pytest.approx(-(c.fc + beyond), abs=1e-12)
    guard = next(g for g in ax.guards(c, mode, 0.0, 0.0) if g.part == "table")
    new = ax.next_mode(c, x, mode, guard, 0.0, 0.0)
    if sticks:
        assert new.sl == 0
        for g in ax.guards(c, new, 0.0, 0.0):
            if g.part == "table":
                assert float(g.row[:ax.N_STATE] @ x + g.row[ax.N_STATE]) >= 0.0, "the stuck mode breaks away at once"
    else:
        assert new.sl == -1
