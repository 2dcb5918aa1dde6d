# SPDX-License-Identifier: MIT
"""What an encoder-only identification can see of one axis, computed from
the physical parameters: the closed form of the plant (sim_models/axis.py)
in steady motion and in rigid-body acceleration, reflected to the motor
shaft, in the voltage domain of the bridge.

Averaged over a carrier period in continuous conduction (a carrier well
above 1 / (2 pi L / R), the armature's corner: 0.2 ms here, so above about
5 kHz) the armature obeys

    d V_supply = R i + k_e w + V_b sgn(i)            (eq. 6-7, brush drop V_b)
    J dw/dt    = k_t i - T_f(sgn w) - b w            (eq. 5, friction at the motor)

with R the winding plus the bridge's two switches.  Hence, per direction,

    w_ss = K (V - V_f(sgn w)),   K = k_t / (k_t k_e + R b),   tau = J R / (k_t k_e + R b)
    V_f  = V_b sgn(i) + R T_f / k_t                       the voltage friction eats

An encoder sees K, tau, V_f+ and V_f- (and the breakaway duty); with the
winding resistance R, which it cannot see, they give k_e (with k_t = k_e,
SI), J and T_f.  In steady motion the gear's and the nut's damping act on
deflection rates, which are zero, so b = 0 for every plant this project
models: the viscous term is reported (as 0) so that an identification that
finds one can be compared.

The dead zone is read at a carrier f: a rotor at rest breaks away when the
torque at the peak of the armature current's ripple exceeds its static
friction and load, so at a finite carrier the breakaway duty is below the
averaged V_break / V_s.  The current's periodic steady state at standstill
is piecewise exponential (on: V_s - V_b across R and L; off, the IBT-2's
brake: -V_b, the current stopping at zero when it reaches it, the
discontinuous conduction of axis.py), so the peak has a closed form per
duty and the breakaway duty is found by bisection.  This holds while the
rotor, once broken away, keeps moving: at carriers well above the
mechanical response (above about 5 kHz here); at low carriers the rotor
breaks away and sticks again within each period, and what counts as
"moves" is then the threshold of the test (the characterisation's
business, not this closed form's).

The friction at the motor shaft T_f collects the rotor's Coulomb friction
and the table's friction and gravity reflected through the screw (R_n) and
the gear: a load the motor drives costs T_out / (xi G) (efficiency xi); a
load that back-drives the motor (z going down under gravity) passes
xi_b T_out / G with the asymmetric efficiency of the ``lab`` plant, and
T_out / (xi G) in the paper's symmetric form (axis.efficiency_form).  The
inertia is the rigid body: the rotor plus everything behind the gear,
accelerated through the gear while the motor drives it (1 / (xi G^2)).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from sim_models.axis import AxisConsts
from sim_models.params import AxisParams, BridgeParams, PlantParams

#: the axis names of the plant file's [identifiable.<axis>] sections, in plant order
AXIS_NAMES = ("x", "z")


@dataclass(frozen=True)
class Identifiable:
    """Per axis: what the encoder sees (voltage domain) and, given R, the
    physical quantities at the motor shaft.  Keys and units as in the plant
    file (docs/plant.md, "The plant file")."""

    speed_gain_rad_per_s_per_v: float
    time_constant_s: float
    friction_v_pos: float
    friction_v_neg: float
    dead_zone_pos_pct: float
    dead_zone_neg_pct: float
    back_emf_v_s_per_rad: float
    inertia_at_motor_kg_m2: float
    coulomb_pos_n_m: float
    coulomb_neg_n_m: float
    viscous_n_m_s_per_rad: float

    def as_dict(self) -> dict[str, float]:
        return {k: float(getattr(self, k)) for k in self.__dataclass_fields__}


def _motor_load(c: AxisConsts, direction: int, table_force_N: float) -> float:
    """Torque the motor must supply (signed, positive direction) to move the
    table steadily in ``direction`` against ``table_force_N`` of friction,
    gravity included: the output needs T_out = R_n (F_friction + m g); the
    efficiency form follows from who drives whom."""
    t_out = c.rn * (direction * table_force_N + c.grav)
    driving = t_out * direction >= 0
    if driving or c.xi_b is None:
        return t_out / (c.xi * c.G)
    return c.xi_b * t_out / c.G


def rigid_inertia_at_motor(c: AxisConsts) -> float:
    """Rotor plus gear output, coupling, screw and table moving as one body
    (the springs undeflected), reflected through the driving gear."""
    j = c.inertia
    behind = j[1] + j[2] + j[3] + (j[5]) * c.rn**2     # table mass m_l moves R_n per screw radian
    return float(j[0] + behind / (c.xi * c.G**2))


def peak_current(c: AxisConsts, supply_v: float, duty: float, carrier_hz: float) -> float:
    """The largest armature current of a stalled rotor's periodic steady state
    at ``duty`` (fraction) and ``carrier_hz`` (the module docstring)."""
    tau_e = c.L / c.R
    t_on, t_off = duty / carrier_hz, (1.0 - duty) / carrier_hz
    i_on, i_b = (supply_v - c.vb) / c.R, c.vb / c.R
    a_on, a_off = math.exp(-t_on / tau_e), math.exp(-t_off / tau_e)
    # continuous conduction: i_min = (i_max + i_b) a_off - i_b, i_max = i_on + (i_min - i_on) a_on
    i_min = ((i_on * (1 - a_on) + i_b) * a_off - i_b) / (1 - a_on * a_off)
    if i_min < 0:                     # the current reaches zero in the off-phase: each period starts from 0
        i_min = 0.0
    return i_on + (i_min - i_on) * a_on


def breakaway_duty(c: AxisConsts, supply_v: float, hold_n_m: float, carrier_hz: float | None) -> float:
    """Smallest duty (fraction) whose peak torque k_t i exceeds ``hold_n_m``
    (None: the averaged model, V_b + R T / k_t over V_s)."""
    if hold_n_m <= 0:
        return 0.0
    if carrier_hz is None:
        return min(1.0, (c.vb + c.R * hold_n_m / c.kt) / supply_v)
    lo, hi = 0.0, 1.0
    if c.kt * peak_current(c, supply_v, hi, carrier_hz) <= hold_n_m:
        return 1.0
    for _ in range(60):
        mid = (lo + hi) / 2
        lo, hi = (lo, mid) if c.kt * peak_current(c, supply_v, mid, carrier_hz) > hold_n_m else (mid, hi)
    return hi


def identifiable(a: AxisParams, bridge: BridgeParams, carrier_hz: float | None = None) -> Identifiable:
    """The closed form above for one axis; the dead zone at ``carrier_hz``
    (None: the averaged model, an infinitely fast carrier)."""
    c = AxisConsts.build(a, bridge)
    b = 0.0
    k_gain = c.kt / (c.kt * c.ke + c.R * b)
    tau = rigid_inertia_at_motor(c) * c.R / (c.kt * c.ke + c.R * b)
    # sliding: the rotor's Coulomb and the table's Coulomb friction
    t_pos = c.tc_m + _motor_load(c, +1, c.fc)
    t_neg = -c.tc_m + _motor_load(c, -1, c.fc)
    vf_pos = c.vb * math.copysign(1.0, t_pos) + c.R * t_pos / c.kt
    vf_neg = -(c.vb * math.copysign(1.0, t_neg) + c.R * t_neg / c.kt)
    # breakaway from rest: the rotor's static friction (the table's static limit is its Coulomb force)
    s_pos = max(c.ts_m, c.tc_m) + _motor_load(c, +1, c.fc)
    s_neg = -max(c.ts_m, c.tc_m) + _motor_load(c, -1, c.fc)
    dz_pos = breakaway_duty(c, bridge.supply_V, s_pos, carrier_hz)
    dz_neg = breakaway_duty(c, bridge.supply_V, -s_neg, carrier_hz)
    return Identifiable(
        speed_gain_rad_per_s_per_v=k_gain,
        time_constant_s=tau,
        friction_v_pos=vf_pos,
        friction_v_neg=vf_neg,
        dead_zone_pos_pct=100.0 * dz_pos,
        dead_zone_neg_pct=100.0 * dz_neg,
        back_emf_v_s_per_rad=c.ke,
        inertia_at_motor_kg_m2=rigid_inertia_at_motor(c),
        coulomb_pos_n_m=t_pos,
        coulomb_neg_n_m=-t_neg,
        viscous_n_m_s_per_rad=b,
    )


def identifiable_plant(p: PlantParams, carrier_hz: float | None = None) -> dict[str, Identifiable]:
    """Both axes, by the plant file's axis names."""
    return {name: identifiable(a, p.bridge, carrier_hz) for name, a in zip(AXIS_NAMES, p.axes)}
