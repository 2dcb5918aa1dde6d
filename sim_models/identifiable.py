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


def identifiable(a: AxisParams, bridge: BridgeParams) -> Identifiable:
    """The closed form above for one axis."""
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
    v_break_pos = c.vb * math.copysign(1.0, s_pos) + c.R * s_pos / c.kt
    v_break_neg = -(c.vb * math.copysign(1.0, s_neg) + c.R * s_neg / c.kt)
    return Identifiable(
        speed_gain_rad_per_s_per_v=k_gain,
        time_constant_s=tau,
        friction_v_pos=vf_pos,
        friction_v_neg=vf_neg,
        dead_zone_pos_pct=100.0 * max(v_break_pos, 0.0) / bridge.supply_V,
        dead_zone_neg_pct=100.0 * max(v_break_neg, 0.0) / bridge.supply_V,
        back_emf_v_s_per_rad=c.ke,
        inertia_at_motor_kg_m2=rigid_inertia_at_motor(c),
        coulomb_pos_n_m=t_pos,
        coulomb_neg_n_m=-t_neg,
        viscous_n_m_s_per_rad=b,
    )


def identifiable_plant(p: PlantParams) -> dict[str, Identifiable]:
    """Both axes, by the plant file's axis names."""
    return {name: identifiable(a, p.bridge) for name, a in zip(AXIS_NAMES, p.axes)}
