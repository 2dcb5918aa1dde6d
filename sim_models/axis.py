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
``(se, cg, cn, sl, sm, gd, bm)``:

- ``se`` electrical: +1 / -1 = conducting with that current sign (decides which
  diode conducts while a bridge side floats), 0 = current held at zero
  (discontinuous conduction: the back-EMF lies between the two diode levels);
- ``cg`` gear mesh (eq 10): +1 / -1 = teeth in contact on that flank, 0 = in
  the backlash gap; always +1 when the backlash is zero;
- ``cn`` nut (eq 11): the same for the axial clearance psi;
- ``sl`` table: +1 / -1 = sliding in that direction with Coulomb friction
  opposing, 0 = stuck (velocity held at zero while the force needed to hold it
  stays within the static limit);
- ``sm`` rotor (brush and bearing friction, the ``lab`` variant): the same
  stick-slip logic on the motor shaft, with a breakaway torque above the
  sliding one; always +1 (no friction, no guards) when the axis has none;
- ``gd`` sign of the mesh torque, which with ``sm`` says whether the motor
  drives the load or the load back-drives the motor (asymmetric gear
  efficiency, ``lab``); always +1 when the efficiency is symmetric.
- ``bm`` brush region of the continuous brush law (``brush_knee_A`` > 0):
  0 = ohmic band |i| < i_k (drop R_b i), +1 / -1 = beyond the knee (drop
  +/- V_b); always 0 with the hard drop, which the terminal levels carry.

Two loads share the motor, brush, rotor friction and gear mesh: ``stage``,
the paper's coupling, screw, nut and table (eq 8-17); and ``dyno``, the
characterisation bench of sec. II.A: a wheel of radius r on the gearbox
output, held by a rope (a spring with damping, the force gauge in series)
to the frame; DOFs 2-5 carry no mass (the positions of 2 and 3 integrate
the current and the rope force, so the bench's instruments read exact means).  The rope is modelled two-sided: it
could only push if the rim came back past the slack point, which the
rotor's friction prevents outside transients near zero force (the bench's
gauge reads the tension, clamped at zero, and counts such moments).

Each mode has *guards*, affine functions g(x) that stay >= 0 while the mode is
valid; :func:`next_mode` says what comes after a guard crosses zero.  The
physics is written once, in :func:`rhs`; the matrices A, b are read off it by
probing (it is exactly affine per mode), so the fast stepper and the
reference solver integrate the same equations by different methods.
"""

from __future__ import annotations

import dataclasses
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
    sm: int = 1
    gd: int = 1
    bm: int = 0


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
    tc_m: float = 0.0    # rotor Coulomb friction (motor shaft)
    ts_m: float = 0.0    # rotor breakaway torque
    vb: float = 0.0      # brush drop
    ib: float = 0.0      # brush knee current (0: the hard drop V_b while current flows)
    xi_b: float | None = None   # back-driving efficiency (None: the paper's symmetric form)
    load: str = "stage"  # "stage" or "dyno"
    r_w: float = 0.0     # dyno: wheel radius
    k_rope: float = 0.0  # dyno: rope + gauge stiffness (N/m)
    b_rope: float = 0.0  # dyno: rope + gauge damping (N s/m)

    @property
    def rotor_friction(self) -> bool:
        return self.ts_m > 0.0 or self.tc_m > 0.0

    @property
    def rotor_modes(self) -> bool:
        """Whether ``sm`` is tracked: with rotor friction (stick-slip), or with
        the asymmetric efficiency (which needs the direction of rotation)."""
        return self.rotor_friction or self.xi_b is not None

    @classmethod
    def build_dyno(cls, a: AxisParams, bridge: BridgeParams, wheel_radius_m: float,
                   wheel_inertia_kg_m2: float, rope_N_per_m: float, rope_N_s_per_m: float) -> "AxisConsts":
        """The motor and gearbox of ``a`` on the dynamometer: gearbox output and
        wheel as one inertia, the rope to the frame; DOFs 2-5 unused."""
        c = cls.build(a, bridge)
        inertia = np.array([a.rotor_inertia_kg_m2, wheel_inertia_kg_m2, 1.0, 1.0, 1.0, 1.0])
        return dataclasses.replace(c, inertia=inertia, load="dyno", r_w=wheel_radius_m, k_rope=rope_N_per_m,
                                   b_rope=rope_N_s_per_m, fc=0.0, grav=0.0)

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
                   inertia=inertia, tc_m=a.motor_coulomb_N_m, ts_m=a.motor_static_N_m,
                   vb=a.brush_drop_V, ib=a.brush_knee_A, xi_b=a.gear_efficiency_back)


def gear_slip(c: AxisConsts, x: np.ndarray) -> tuple[float, float]:
    """Mesh deflection at the output side, d = phi_m/G - phi_g, and its rate."""
    return x[PHI_M] / c.G - x[PHI_G], x[W_M] / c.G - x[W_G]


def nut_slip(c: AxisConsts, x: np.ndarray) -> tuple[float, float]:
    """eq (11): eps = chi_l - R_n phi_s - chi_s, and its rate."""
    return (x[CHI_L] - c.rn * x[PHI_S] - x[CHI_S],
            x[V_L] - c.rn * x[W_S] - x[V_S])


def mesh_torque(c: AxisConsts, x: np.ndarray, mode: Mode) -> float:
    """Mesh torque T_g at the output side (eq 10 with the dead zone of
    half-width delta; 0 in the gap).  b_g acts on the motor-side slip
    phi_m' - G phi_g' = G d' (paper's D_f), so on the output side it is
    b_g G^2 d'."""
    if mode.cg == 0:
        return 0.0
    d, dd = gear_slip(c, x)
    return c.kg * (d - mode.cg * c.delta) + c.bg * c.G**2 * dd


def efficiency_form(c: AxisConsts, mode: Mode) -> tuple[float, float]:
    """(a_m, a_o): the motor feels -a_m T_g / G, the gearbox output +a_o T_g.
    The paper's form is (1, xi) whichever way power flows.  With a
    back-driving efficiency (``lab``): driving (the rotor turns the way its
    mesh torque pushes) (1, xi); back-driven (xi_b, 1), so the motor
    receives only xi_b of what the load delivers; a stuck rotor passes the
    paper's (1, xi) to the output (its hold torques take each direction's
    form: :func:`rotor_hold_torque`)."""
    if c.xi_b is None or mode.sm == 0 or mode.sm == mode.gd:
        return 1.0, c.xi
    return c.xi_b, 1.0


def forces(c: AxisConsts, x: np.ndarray, mode: Mode) -> np.ndarray:
    """Generalised forces on the six mechanical DOF, table and rotor
    Coulomb friction excluded."""
    f = np.zeros(NPOS)
    if mode.cg != 0:
        tg = mesh_torque(c, x, mode)
        a_m, a_o = efficiency_form(c, mode)
        f[0] -= a_m * tg / c.G
        f[1] += a_o * tg             # efficiency: only xi of the mesh torque arrives
    f[0] += c.kt * x[I_]             # eq (5)
    if c.load == "dyno":
        f[1] -= c.r_w * rope_tension(c, x)
        return f
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
    return f


def rope_tension(c: AxisConsts, x: np.ndarray) -> float:
    """Dyno: the force in the rope, what the gauge's spring carries
    (negative: the rim came back past the slack point)."""
    return c.k_rope * c.r_w * x[PHI_G] + c.b_rope * c.r_w * x[W_G]


def rhs(c: AxisConsts, x: np.ndarray, mode: Mode, e_pos: float, e_neg: float) -> np.ndarray:
    """dx/dt in the given mode with the bridge presenting (e_pos, e_neg)."""
    dx = np.empty(N_STATE)
    f = forces(c, x, mode)
    if mode.sl == 0:
        f[5] = 0.0                   # stuck: held by static friction
    else:
        f[5] -= mode.sl * c.fc       # sliding: Coulomb force opposes the motion
    if c.rotor_modes:
        if mode.sm == 0:
            f[0] = 0.0               # rotor stuck: brushes and bearings hold it
        else:
            f[0] -= mode.sm * c.tc_m
    dx[1:7] = x[7:13]
    dx[7:13] = f / c.inertia
    if c.load == "dyno":
        # the instruments' exact means: DOFs 2 and 3 are unused on the dyno,
        # their positions integrate the current and the rope force
        dx[PHI_C] = x[I_]
        dx[PHI_S] = rope_tension(c, x)
    if mode.se == 0:
        dx[0] = 0.0                  # no diode conducts: i stays 0
    else:
        e = e_pos if mode.se > 0 else e_neg
        if c.ib > 0.0:               # continuous brush law: ohmic, then V_b beyond the knee
            vbr = mode.bm * c.vb if mode.bm else (c.vb / c.ib) * x[I_]
            dx[0] = (e - c.R * x[I_] - c.ke * x[W_M] - vbr) / c.L
        else:
            dx[0] = (e - c.R * x[I_] - c.ke * x[W_M]) / c.L     # eq (6)-(7)
    return dx


def table_hold_force(c: AxisConsts, x: np.ndarray, mode: Mode) -> float:
    """Force the static friction must supply to keep the table at rest."""
    return float(forces(c, x, mode)[5])


def rotor_hold_torque(c: AxisConsts, x: np.ndarray, mode: Mode, direction: int) -> float:
    """Net torque on the rotor (its Coulomb friction excluded) were it to
    move in ``direction`` (+1 / -1): what its static friction must hold.  The
    two directions differ only with the asymmetric efficiency: moving against
    the mesh torque the load back-drives the gearbox, which passes only xi_b
    of it, so the gearbox's own friction helps hold the rotor."""
    return float(forces(c, x, mode._replace(sm=direction))[0])


#: a rotor breaks away only beyond its band by this much (N m, motor side).
#: With no rotor friction the band is the gearbox's own (xi_b T_g .. T_g) and
#: can be zero wide; without the margin a state resting on its edge (net
#: torque zero to rounding) switched stuck/sliding at every step (Zeno).
#: The margin must also exceed the net torque that event location leaves at a
#: velocity reversal: a stop is found to a 10 ns tick, in which a rotor on
#: the stiff mesh gains about 1e-5 rad/s, and the net torque at the stop
#: then lies a few 1e-9 N m outside the gearbox's band, which is
#: (1 - xi_b) |T_g| / G, about 3e-8 N m for a rotor at rest on a tiny load.
#: At 1e-9 N m a rotor without friction of its own (gear efficiency alone)
#: ping-ponged stuck -> forward -> back -> forward -> stuck about 90 times per
#: 25 ms control sample on axis x under P (41 000 switches in 20 s, half the
#: run's CPU); at 1e-8 N m it sticks (109 switches).  1e-8 N m is 3e-7 of
#: a stall torque and 1e-5 of the lab rotor's breakaway torque.
ROTOR_BREAKAWAY_MARGIN = 1e-8


#: a sliding table sticks when the force on it is within its Coulomb force plus
#: this (N): when the force beyond the friction is zero to rounding, the table
#: would slide on with no acceleration and its velocity guard fire again at
#: once, without end (Zeno; met on axis z under PD at a 50 Hz carrier, the
#: force 5e-14 N beyond 0.17 N).  1e-9 N is 6e-9 of axis z's friction force.
TABLE_BREAKAWAY_MARGIN = 1e-9


def rotor_stick_or_slide(c: AxisConsts, x: np.ndarray, mode: Mode) -> int:
    """sm for a rotor at rest: +1 / -1 if the net torque towards that side
    breaks away, else 0 (stuck).  At most one side can break away.  Without
    rotor friction (ts = 0) the band is the gearbox's own: with the
    asymmetric efficiency a load can be held between xi_b T_g and T_g."""
    band = c.ts_m + ROTOR_BREAKAWAY_MARGIN
    if rotor_hold_torque(c, x, mode, 1) > band:
        return 1
    if rotor_hold_torque(c, x, mode, -1) < -band:
        return -1
    return 0


def terminal_levels(c: AxisConsts, e_pos: float, e_neg: float) -> tuple[float, float]:
    """The bridge's armature voltages (while i > 0, while i < 0) less the
    brush drop, which opposes the current while it flows: every function of
    this module takes these levels.  With a drop the current can stop at zero
    even with both bridge sides driven (discontinuous conduction), exactly as
    while a side floats.  The continuous brush law (``ib`` > 0) is not a
    level: :func:`rhs` applies it by the brush region ``bm``."""
    if c.vb == 0.0 or c.ib > 0.0:
        return e_pos, e_neg
    return e_pos - c.vb, e_neg + c.vb


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
    if c.load == "dyno":
        pass                         # the rope is a two-sided spring: no mode
    elif mode.sl > 0:
        out.append(Guard("table", 0, _linear_row(lambda z: z[V_L], c), 1e-9))
    elif mode.sl < 0:
        out.append(Guard("table", 0, _linear_row(lambda z: -z[V_L], c), 1e-9))
    else:
        hold = lambda z: table_hold_force(c, z, mode)  # noqa: E731
        limit = c.fc + TABLE_BREAKAWAY_MARGIN
        out.append(Guard("table", 0, _linear_row(lambda z: limit - hold(z), c), 1e-6))
        out.append(Guard("table", 1, _linear_row(lambda z: limit + hold(z), c), 1e-6))
    if c.rotor_modes:
        if mode.sm > 0:
            out.append(Guard("rotor", 0, _linear_row(lambda z: z[W_M], c), 1e-9))
        elif mode.sm < 0:
            out.append(Guard("rotor", 0, _linear_row(lambda z: -z[W_M], c), 1e-9))
        else:
            band = c.ts_m + ROTOR_BREAKAWAY_MARGIN
            out.append(Guard("rotor", 0, _linear_row(lambda z: band - rotor_hold_torque(c, z, mode, 1), c), 1e-12))
            out.append(Guard("rotor", 1, _linear_row(lambda z: band + rotor_hold_torque(c, z, mode, -1), c), 1e-12))
    if c.ib > 0.0 and mode.se != 0:
        if mode.bm > 0:
            out.append(Guard("brush", 0, _linear_row(lambda z: z[I_] - c.ib, c), 1e-9))
        elif mode.bm < 0:
            out.append(Guard("brush", 0, _linear_row(lambda z: -z[I_] - c.ib, c), 1e-9))
        else:
            out.append(Guard("brush", 0, _linear_row(lambda z: c.ib - z[I_], c), 1e-9))
            out.append(Guard("brush", 1, _linear_row(lambda z: z[I_] + c.ib, c), 1e-9))
    if c.xi_b is not None and mode.cg != 0:
        # the mesh torque changing sign turns driving into back-driving
        out.append(Guard("mesh", 0, _linear_row(lambda z: mode.gd * mesh_torque(c, z, mode), c), 1e-12))
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
    m = Mode(elec_mode(c, x, e_pos, e_neg), cg, cn, 0, bm=brush_region(c, x))
    m = m._replace(gd=_mesh_sign(c, x, m))
    if c.rotor_modes:
        m = m._replace(sm=_sign(x[W_M]) if x[W_M] != 0.0 else rotor_stick_or_slide(c, x, m))
    if c.load == "dyno":
        return m
    if x[V_L] != 0.0:
        return m._replace(sl=_sign(x[V_L]))
    h = table_hold_force(c, x, m)
    return m._replace(sl=0 if abs(h) <= c.fc + TABLE_BREAKAWAY_MARGIN else _sign(h))


def brush_region(c: AxisConsts, x: np.ndarray) -> int:
    """bm for a state: 0 in the ohmic band (or with the hard drop), else the
    current's sign."""
    if c.ib <= 0.0 or abs(x[I_]) < c.ib:
        return 0
    return _sign(x[I_])


def _mesh_sign(c: AxisConsts, x: np.ndarray, mode: Mode) -> int:
    """gd for a state: the mesh torque's sign (1 at zero), when it matters."""
    if c.xi_b is None:
        return 1
    return -1 if mesh_torque(c, x, mode) < 0 else 1


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
        m = mode._replace(cg=new) if g.part == "gear" else mode._replace(cn=new)
        return m._replace(gd=_mesh_sign(c, x, m))
    if g.part == "mesh":
        return mode._replace(gd=-mode.gd)   # the mesh torque changed sign
    if g.part == "brush":
        if mode.bm != 0:
            return mode._replace(bm=0)      # back into the ohmic band
        return mode._replace(bm=1 if g.index == 0 else -1)
    if g.part == "rotor":
        x[W_M] = 0.0
        if mode.sm == 0:             # broke away: guard 0 forwards, guard 1 backwards
            return mode._replace(sm=1 if g.index == 0 else -1)
        # speed reached zero: the brushes hold it, or it turns back
        return mode._replace(sm=rotor_stick_or_slide(c, x, mode))
    # table
    x[V_L] = 0.0
    h = table_hold_force(c, x, mode)
    if mode.sl != 0 and abs(h) <= c.fc + TABLE_BREAKAWAY_MARGIN:
        return mode._replace(sl=0)   # velocity reached zero and friction can hold it
    if mode.sl == 0:                 # guard 0: hold > fc, guard 1: hold < -fc
        return mode._replace(sl=1 if g.index == 0 else -1)
    return mode._replace(sl=_sign(h))
