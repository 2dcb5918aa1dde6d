# SPDX-License-Identifier: MIT
"""One axis of the stage as a piecewise-affine hybrid system (paper eq 5-17).

State vector (SI), ``N_STATE`` = 13 entries::

    0 i      armature current (A)
    1 phi_m  motor rotor angle (rad, motor side)
    2 phi_g  gearbox output angle (rad)
    3 phi_c  coupling angle (rad)
    4 phi_s  screw angle (rad)
    5 chi_s  screw axial deflection (m)
    6 chi_l  table position (m)
    7..12    the six velocities, same order

Within one *mode* the right-hand side is affine, dx/dt = A x + b.  A mode is
``(se, cg, cn, sl)``:

- ``se`` electrical: +1 / -1 = conducting with that current sign (decides which
  diode conducts while a bridge side floats), 0 = current held at zero
  (discontinuous conduction: the back-EMF lies between the two diode levels);
- ``cg`` gear mesh (eq 10): +1 / -1 = teeth in contact on that flank, 0 = in
  the backlash gap; always +1 when the backlash is zero;
- ``cn`` nut (eq 11): the same for the axial clearance psi;
- ``sl`` table: +1 / -1 = sliding in that direction with Coulomb friction
  opposing, 0 = stuck (velocity held at zero while the force needed to hold it
  stays within the static limit).

Each mode has *guards*, affine functions g(x) that stay >= 0 while the mode is
valid; :func:`next_mode` says what comes after a guard crosses zero.  The
physics is written once, in :func:`rhs`; the matrices A, b are read off it by
probing (it is exactly affine per mode), so the fast stepper and the
reference solver integrate the same equations by different methods.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from sim_models.params import AxisParams, BridgeParams

N_STATE = 13
I_, PHI_M, PHI_G, PHI_C, PHI_S, CHI_S, CHI_L = range(7)
W_M, W_G, W_C, W_S, V_S, V_L = range(7, 13)
NPOS = 6


class Mode(NamedTuple):
    se: int
    cg: int
    cn: int
    sl: int


@dataclass(frozen=True)
class AxisConsts:
    """Everything :func:`rhs` needs, precomputed from the parameters."""

    L: float
    R: float             # armature + bridge path
    ke: float
    kt: float            # motor-side torque constant k_m / (xi G)
    G: float
    xi: float
    kg: float
    bg: float
    delta: float
    kc: float
    ks: float
    kr: float
    br: float
    rn: float
    kn: float
    bn: float
    psi: float
    fc: float            # table Coulomb force (= static limit)
    grav: float          # m_l g, acting towards negative chi_l
    inertia: np.ndarray  # diagonal of the mass matrix, 6 entries

    @classmethod
    def build(cls, a: AxisParams, bridge: BridgeParams) -> "AxisConsts":
        gamma = a.gear_efficiency * a.gear_ratio
        ic3 = a.coupling_inertia_kg_m2 / 3.0
        inertia = np.array([
            a.rotor_inertia_kg_m2,
            a.rotor_inertia_kg_m2 / gamma**2 + ic3,   # eq 17, second line
            ic3,
            ic3 + a.screw_inertia_kg_m2,
            a.screw_mass_kg + a.table_mass_kg,        # eq 8: (m_s + m_l) chi_s'^2
            a.table_mass_kg,
        ])
        return cls(L=a.inductance_H, R=a.resistance_ohm + 2.0 * bridge.r_on_ohm,
                   ke=a.ke_V_s_per_rad, kt=a.kt_motor_N_m_per_A, G=a.gear_ratio,
                   xi=a.gear_efficiency, kg=a.gear_stiffness_N_m_per_rad,
                   bg=a.gear_damping_N_m_s_per_rad, delta=a.gear_backlash_rad,
                   kc=a.coupling_stiffness_N_m_per_rad, ks=a.screw_torsion_N_m_per_rad,
                   kr=a.screw_axial_N_per_m, br=a.screw_axial_damping_N_s_per_m,
                   rn=a.screw_m_per_rad, kn=a.nut_stiffness_N_per_m,
                   bn=a.nut_damping_N_s_per_m, psi=a.nut_clearance_m,
                   fc=a.table_coulomb_N, grav=a.table_mass_kg * a.gravity_m_s2,
                   inertia=inertia)


def gear_slip(c: AxisConsts, x: np.ndarray) -> tuple[float, float]:
    """Mesh deflection at the output side, d = phi_m/G - phi_g, and its rate."""
    return x[PHI_M] / c.G - x[PHI_G], x[W_M] / c.G - x[W_G]


def nut_slip(c: AxisConsts, x: np.ndarray) -> tuple[float, float]:
    """eq (11): eps = chi_l - R_n phi_s - chi_s, and its rate."""
    return (x[CHI_L] - c.rn * x[PHI_S] - x[CHI_S],
            x[V_L] - c.rn * x[W_S] - x[V_S])


def forces(c: AxisConsts, x: np.ndarray, mode: Mode) -> np.ndarray:
    """Generalised forces on the six mechanical DOF, table friction excluded."""
    f = np.zeros(NPOS)
    d, dd = gear_slip(c, x)
    if mode.cg != 0:
        # eq (10) with the dead zone of half-width delta; b_g acts on the
        # motor-side slip phi_m' - G phi_g' = G d' (paper's D_f), so on the
        # output side it is b_g G^2 d'.
        tg = c.kg * (d - mode.cg * c.delta) + c.bg * c.G**2 * dd
        f[0] -= tg / c.G
        f[1] += c.xi * tg            # efficiency: only xi of the mesh torque arrives
    tc = c.kc * (x[PHI_G] - x[PHI_C])
    f[1] -= tc
    f[2] += tc
    ts = c.ks * (x[PHI_C] - x[PHI_S])
    f[2] -= ts
    f[3] += ts
    e, de = nut_slip(c, x)
    if mode.cn != 0:
        fn = c.kn * (e - mode.cn * c.psi) + c.bn * de
        f[3] += c.rn * fn
        f[4] += fn
        f[5] -= fn
    f[4] -= c.kr * x[CHI_S] + c.br * x[V_S]
    f[5] -= c.grav
    f[0] += c.kt * x[I_]             # eq (5)
    return f


def rhs(c: AxisConsts, x: np.ndarray, mode: Mode, e_pos: float, e_neg: float) -> np.ndarray:
    """dx/dt in the given mode with the bridge presenting (e_pos, e_neg)."""
    dx = np.empty(N_STATE)
    f = forces(c, x, mode)
    if mode.sl == 0:
        f[5] = 0.0                   # stuck: held by static friction
    else:
        f[5] -= mode.sl * c.fc       # sliding: Coulomb force opposes the motion
    dx[1:7] = x[7:13]
    dx[7:13] = f / c.inertia
    if mode.se == 0:
        dx[0] = 0.0                  # no diode conducts: i stays 0
    else:
        e = e_pos if mode.se > 0 else e_neg
        dx[0] = (e - c.R * x[I_] - c.ke * x[W_M]) / c.L     # eq (6)-(7)
    return dx


def table_hold_force(c: AxisConsts, x: np.ndarray, mode: Mode) -> float:
    """Force the static friction must supply to keep the table at rest."""
    return float(forces(c, x, mode)[5])


def affine(c: AxisConsts, mode: Mode, e_pos: float, e_neg: float) -> tuple[np.ndarray, np.ndarray]:
    """(A, b) with rhs = A x + b in this mode, read off rhs by probing."""
    z = np.zeros(N_STATE)
    b = rhs(c, z, mode, e_pos, e_neg)
    a = np.empty((N_STATE, N_STATE))
    for j in range(N_STATE):
        z[j] = 1.0
        a[:, j] = rhs(c, z, mode, e_pos, e_neg) - b
        z[j] = 0.0
    return a, b


def _linear_row(fun, c: AxisConsts) -> np.ndarray:
    """Affine function of x as a row over [x, 1]."""
    z = np.zeros(N_STATE)
    row = np.empty(N_STATE + 1)
    row[N_STATE] = fun(z)
    for j in range(N_STATE):
        z[j] = 1.0
        row[j] = fun(z) - row[N_STATE]
        z[j] = 0.0
    return row


class Guard(NamedTuple):
    part: str        # "elec", "gear", "nut", "table"
    index: int
    row: np.ndarray  # g = row . [x, 1] >= 0 while the mode holds
    tol: float


def guards(c: AxisConsts, mode: Mode, e_pos: float, e_neg: float) -> list[Guard]:
    out: list[Guard] = []
    if e_pos != e_neg:               # a side floats: the current sign matters
        if mode.se > 0:
            out.append(Guard("elec", 0, _linear_row(lambda z: z[I_], c), 1e-9))
        elif mode.se < 0:
            out.append(Guard("elec", 0, _linear_row(lambda z: -z[I_], c), 1e-9))
        else:
            out.append(Guard("elec", 0, _linear_row(lambda z: c.ke * z[W_M] - e_pos, c), 1e-7))
            out.append(Guard("elec", 1, _linear_row(lambda z: e_neg - c.ke * z[W_M], c), 1e-7))
    for part, val, half, on in (("gear", lambda z: gear_slip(c, z)[0], c.delta, mode.cg),
                                ("nut", lambda z: nut_slip(c, z)[0], c.psi, mode.cn)):
        if half == 0.0:
            continue
        if on > 0:
            out.append(Guard(part, 0, _linear_row(lambda z, v=val, h=half: v(z) - h, c), 1e-13))
        elif on < 0:
            out.append(Guard(part, 1, _linear_row(lambda z, v=val, h=half: -v(z) - h, c), 1e-13))
        else:
            out.append(Guard(part, 0, _linear_row(lambda z, v=val, h=half: h - v(z), c), 1e-13))
            out.append(Guard(part, 1, _linear_row(lambda z, v=val, h=half: v(z) + h, c), 1e-13))
    if mode.sl > 0:
        out.append(Guard("table", 0, _linear_row(lambda z: z[V_L], c), 1e-9))
    elif mode.sl < 0:
        out.append(Guard("table", 0, _linear_row(lambda z: -z[V_L], c), 1e-9))
    else:
        hold = lambda z: table_hold_force(c, z, mode)  # noqa: E731
        out.append(Guard("table", 0, _linear_row(lambda z: c.fc - hold(z), c), 1e-6))
        out.append(Guard("table", 1, _linear_row(lambda z: c.fc + hold(z), c), 1e-6))
    return out


def _sign(v: float) -> int:
    return 1 if v > 0 else (-1 if v < 0 else 0)


def elec_mode(c: AxisConsts, x: np.ndarray, e_pos: float, e_neg: float) -> int:
    """Electrical mode from the state: the current's sign, or at zero current
    the direction the bridge would push it (0 if no diode can conduct)."""
    if x[I_] != 0.0:
        return _sign(x[I_])
    if e_pos == e_neg:
        return 1                     # both sides driven: the sign does not matter
    eb = c.ke * x[W_M]
    if e_pos > eb:
        return 1
    if e_neg < eb:
        return -1
    return 0


def initial_mode(c: AxisConsts, x: np.ndarray, e_pos: float, e_neg: float) -> Mode:
    """Mode of a state that is not on a switching surface (or at rest)."""
    d = gear_slip(c, x)[0]
    e = nut_slip(c, x)[0]
    cg = 1 if c.delta == 0 else (1 if d > c.delta else (-1 if d < -c.delta else 0))
    cn = 1 if c.psi == 0 else (1 if e > c.psi else (-1 if e < -c.psi else 0))
    m = Mode(elec_mode(c, x, e_pos, e_neg), cg, cn, 0)
    if x[V_L] != 0.0:
        return m._replace(sl=_sign(x[V_L]))
    h = table_hold_force(c, x, m)
    return m._replace(sl=0 if abs(h) <= c.fc else _sign(h))


def next_mode(c: AxisConsts, x: np.ndarray, mode: Mode, g: Guard,
              e_pos: float, e_neg: float) -> Mode:
    """The mode after guard ``g`` of ``mode`` crossed zero at state ``x``.
    ``x`` is modified in place to sit exactly on the new mode's constraint
    (i = 0 or table velocity = 0)."""
    if g.part == "elec":
        if mode.se != 0:             # current reached zero while a side floats
            x[I_] = 0.0
            return mode._replace(se=elec_mode(c, x, e_pos, e_neg))
        return mode._replace(se=1 if g.index == 0 else -1)
    if g.part in ("gear", "nut"):
        cur = mode.cg if g.part == "gear" else mode.cn
        new = 0 if cur != 0 else (1 if g.index == 0 else -1)
        return mode._replace(cg=new) if g.part == "gear" else mode._replace(cn=new)
    # table
    x[V_L] = 0.0
    h = table_hold_force(c, x, mode)
    if mode.sl != 0 and abs(h) <= c.fc:
        return mode._replace(sl=0)   # velocity reached zero and friction can hold it
    if mode.sl == 0:                 # guard 0: hold > fc, guard 1: hold < -fc
        return mode._replace(sl=1 if g.index == 0 else -1)
    return mode._replace(sl=_sign(h))
