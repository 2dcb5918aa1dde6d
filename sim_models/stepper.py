# SPDX-License-Identifier: MIT
"""Fast plant stepper for co-simulation: exact zero-order-hold flow per mode.

Between mode switches each axis is linear time-invariant with a constant
bridge voltage, so its flow over a time tau is exactly ``expm(M tau)`` of the
augmented matrix ``M = [[A, b], [0, 0]]`` acting on ``[x, 1]``.  The stepper
caches these matrices per (mode, bridge voltages, length in ticks), so a
co-simulation that steps at PWM edges or fixed periods reuses a handful of
them.  Mode switches (current reaching zero while a bridge side floats, gear
backlash and nut clearance contacts, table stick/slip) are events: after each
chunk (at most ``h_max_s`` long) the guards are checked at the chunk end and,
through a cubic Hermite fit of the guard using its exact time derivatives,
for a dip inside the chunk; the crossing is then located by bracketed
false-position iteration on the exact flow, the mode switched and the rest of
the chunk integrated in the new mode.

Co-simulation API (sim_models.stepper.TwoAxisPlant)::

    plant = TwoAxisPlant()                      # Table 2 parameters
    edges = plant.advance(dt, (pins_x, pins_z)) # Pins(rpwm, lpwm, r_en, l_en) each
    for t, axis, a, b, z in edges: ...          # t: seconds after the call's start
    plant.table_mm(0), plant.screw_angle(1), plant.current(0), plant.is_currents(0)

A caller that reads the plant only between control periods and knows each
period's pin changes in advance (the experiment's fast path) gives them all
at once, ``plant.run_pins(ticks, changes_per_axis)``: no encoder edges, and
many chunks integrated before their guards are checked in one product
(``FastAxis.run_pins``; docs/plant.md, "The fast path").

Time advances in integers of ``tick_s`` (default 10 ns); the running total
of the requested dt is rounded (not each dt), so the plant never drifts from
the caller's clock by more than half a tick.
"""

from __future__ import annotations

import bisect
import math
import random
from dataclasses import dataclass, field
from typing import Sequence

import numpy as np
from scipy.linalg import matrix_balance

from sim_models import axis as ax
from sim_models.bridge import COAST, Pins, armature_voltages, is_currents
from sim_models.encoder import Edge, add_glitches, count_of, edges_from_samples, hermite, pins_of
from sim_models.params import AxisParams, PlantParams, load_params

NZ = ax.N_STATE + 1


@dataclass
class _ModeSystem:
    mode: ax.Mode
    e_pos: float
    e_neg: float
    m: np.ndarray                  # augmented 14 x 14
    guards: list[ax.Guard]
    g: np.ndarray | None           # guard rows, n_g x 14
    gm: np.ndarray | None          # g @ m: time derivative of the guards
    tol: np.ndarray | None
    phi: dict[int, np.ndarray]     # ticks -> expm(m * ticks * tick)
    bal: np.ndarray                # diagonal similarity that balances m
    mb: np.ndarray                 # the balanced matrix
    h_ticks: int                   # longest chunk between guard checks
    digits: dict[tuple[int, int], np.ndarray] = field(default_factory=dict)
    gg: np.ndarray | None = None   # [g; g m]: guards and their derivatives in one product
    tol_list: list[float] | None = None
    # current integrals (FastAxis(energy=True)): per digit and per whole-tick
    # length, (r, G) with r z = integral of i, z' G z = integral of i^2
    idigits: dict[tuple[int, int], tuple[np.ndarray, np.ndarray]] = field(default_factory=dict)
    icache: dict[int, tuple[np.ndarray, np.ndarray, np.ndarray]] = field(default_factory=dict)
    iseen: set[int] = field(default_factory=set)   # lengths met once (the second time they are cached)
    hpow: np.ndarray | None = None  # flows of 1, 2, ... whole chunks (FastAxis._powers)

    def __post_init__(self) -> None:
        if self.g is not None and self.gm is not None and self.tol is not None:
            self.gg = np.vstack([self.g, self.gm])
            self.tol_list = self.tol.tolist()

    def expm(self, tau: float) -> np.ndarray:
        """expm(m tau) through the balanced matrix (see :func:`expm_balanced`)."""
        return expm_balanced(self.mb, self.bal, tau)


class FastAxis:
    """One axis advanced by exact ZOH with event handling."""

    MAX_EVENTS_PER_CHUNK = 10_000

    def __init__(self, a: AxisParams, plant: PlantParams, axis_index: int = 0,
                 h_max_s: float = 1e-3, tick_s: float = 1e-8,
                 h_contact_s: float = 1e-5, h_mesh_s: float = 5e-5, consts: ax.AxisConsts | None = None,
                 encoder: bool = True, energy: bool = False) -> None:
        self.params = a
        self.bridge = plant.bridge
        self.enc = plant.encoder
        self.index = axis_index
        # consts: another load for the same motor (AxisConsts.build_dyno)
        self.c = consts or ax.AxisConsts.build(a, plant.bridge)
        self.encoder = encoder
        # the winding's temperature rise over ambient (K) and the winding
        # resistance the mode matrices were built with (heats: R(T))
        self.heats = a.heats
        self.theta = 0.0
        self._r_wind = a.resistance_ohm
        if self.heats:
            energy = True            # the heating is the exact integral of i^2 R
        # the bridge's output edges, delayed (bridge_timing): pending
        # (tick, pins) changes of the outputs, and the pins the outputs show
        self.timing = plant.bridge.timing_in_plant
        self._sched: tuple[tuple[int, Pins], ...] = ()
        self._cmd_pins = COAST
        # energy: keep the exact integrals of the current and of its square
        # (copper loss, ripple) through every flow, events included
        self.energy = energy
        self.q_i = 0.0              # integral of i dt (A s)
        self.q_i2 = 0.0             # integral of i^2 dt (A^2 s)
        self.tick = tick_s
        self.h_max_ticks = max(1, round(h_max_s / tick_s))
        # backlash and clearance contacts bounce at kHz rates: check them often
        self.h_contact_ticks = max(1, min(self.h_max_ticks, round(h_contact_s / tick_s)))
        # the mesh torque's sign (asymmetric efficiency) flips with the
        # drivetrain's kHz modes near zero load: check it every 50 us
        self.h_mesh_ticks = max(1, min(self.h_max_ticks, round(h_mesh_s / tick_s)))
        self.z = np.zeros(NZ)
        self.z[ax.N_STATE] = 1.0
        self.pins = COAST           # what the bridge's outputs show
        self.e_pos, self.e_neg = ax.terminal_levels(self.c, *armature_voltages(COAST, self.bridge))
        self.mode = ax.initial_mode(self.c, self.z[:ax.N_STATE], self.e_pos, self.e_neg)
        self.count = count_of(0.0, self.enc)
        self._systems: dict[tuple[ax.Mode, float, float], _ModeSystem] = {}
        self._pin_levels: dict[Pins, tuple[float, float]] = {}
        self.events = 0             # mode switches handled (for benchmarks)
        self._t_req = 0.0           # time asked for so far (s)
        self._ticks = 0             # time advanced so far (ticks)
        self._s = np.linspace(0.0, 1.0, 17)

    # ---- state ---------------------------------------------------------
    @property
    def x(self) -> np.ndarray:
        return self.z[:ax.N_STATE]

    def set_state(self, x: np.ndarray) -> None:
        self.z[:ax.N_STATE] = x
        self.mode = ax.initial_mode(self.c, self.z[:ax.N_STATE], self.e_pos, self.e_neg)
        self.count = count_of(float(x[ax.PHI_M]), self.enc)

    #: what advance() changes besides the state vector (snapshot / restore)
    _STATE_FIELDS = ("pins", "e_pos", "e_neg", "mode", "count", "events", "_t_req", "_ticks", "q_i", "q_i2",
                     "theta", "_sched", "_cmd_pins", "_r_wind", "c", "_systems")

    def snapshot(self) -> tuple:
        """Everything :meth:`advance` changes, to undo a speculative step."""
        return self.z.copy(), tuple(getattr(self, f) for f in self._STATE_FIELDS)

    def restore(self, snap: tuple) -> None:
        z, vals = snap
        self.z = z.copy()
        for f, v in zip(self._STATE_FIELDS, vals):
            setattr(self, f, v)

    def set_voltage(self, volts: float) -> None:
        """Drive the armature from an ideal voltage source instead of the bridge
        (the paper's simulation: the PWM averaged over its period, eq. 23-25).
        Both terminals are driven, so only a brush drop can stop the current."""
        key = ("V", volts)
        if self.pins == key:
            return
        self.pins = key  # type: ignore[assignment]
        self.e_pos, self.e_neg = ax.terminal_levels(self.c, volts, volts)
        self.mode = self.mode._replace(
            se=ax.elec_mode(self.c, self.z[:ax.N_STATE], self.e_pos, self.e_neg))
        if len(self._systems) > 512:     # every sample brings a new voltage
            self._systems.clear()

    def set_pins(self, pins: Pins) -> None:
        if self.timing:
            self._command(pins)
            return
        self._apply_pins(pins)

    def _command(self, pins: Pins) -> None:
        """A pin change at the bridge's inputs, now (bridge_timing): the
        outputs follow after the turn-on delay when the change starts a
        driving phase, after the turn-off delay otherwise; a driving phase
        whose output would be shorter than the minimum pulse is dropped."""
        prev = self._cmd_pins
        if pins == prev:
            return
        self._cmd_pins = pins
        b = self.bridge
        now = self._ticks
        starts = _driving(pins) and not _driving(prev)
        at = now + round((b.turn_on_delay_s if starts else b.turn_off_delay_s) / self.tick)
        sched = [e for e in self._sched if e[0] < at]   # a later edge overtakes the pending ones
        if _driving(prev) and not _driving(pins):
            ons = [k for k, (t, p) in enumerate(sched) if _driving(p)]
            if ons and (at - sched[ons[-1]][0]) * self.tick < b.min_pulse_s:
                del sched[ons[-1]:]                     # the pulse never reaches the rail
                self._sched = tuple(sched)
                return
        sched.append((at, pins))
        self._sched = tuple(sched)

    def _apply_pins(self, pins: Pins) -> None:
        if pins == self.pins:
            return
        self.pins = pins
        self.e_pos, self.e_neg = ax.terminal_levels(self.c, *armature_voltages(pins, self.bridge))
        self.mode = self.mode._replace(
            se=ax.elec_mode(self.c, self.z[:ax.N_STATE], self.e_pos, self.e_neg))

    # ---- flow ----------------------------------------------------------
    def _system(self, key: tuple[ax.Mode, float, float] | None = None) -> _ModeSystem:
        """The flow data of (mode, e_pos, e_neg), by default the axis's own, built on first use."""
        key = key or (self.mode, self.e_pos, self.e_neg)
        s = self._systems.get(key)
        if s is None:
            mode, e_pos, e_neg = key
            a, b = ax.affine(self.c, mode, e_pos, e_neg)
            m = np.zeros((NZ, NZ))
            m[:ax.N_STATE, :ax.N_STATE] = a
            m[:ax.N_STATE, ax.N_STATE] = b
            gl = ax.guards(self.c, mode, e_pos, e_neg)
            g = np.array([x.row for x in gl]) if gl else None
            _, (bal, _) = matrix_balance(m, permute=False, separate=True)
            s = _ModeSystem(mode, e_pos, e_neg, m, gl, g,
                            None if g is None else g @ m,
                            None if g is None else np.array([x.tol for x in gl]), {},
                            bal, m * bal[None, :] / bal[:, None],
                            self.h_contact_ticks if any(x.part in ("gear", "nut") for x in gl)
                            # the mesh sign changes the dynamics only while the rotor turns
                            # (a stuck rotor passes the same torque either way)
                            else self.h_mesh_ticks if mode.sm != 0 and any(x.part == "mesh" for x in gl)
                            else self.h_max_ticks)
            self._systems[key] = s
        return s

    def _flow(self, s: _ModeSystem, ticks: int) -> np.ndarray:
        """expm(m * ticks * tick), cached per length (:meth:`_compose`)."""
        p = s.phi.get(ticks)
        if p is None:
            if len(s.phi) > 4096:
                s.phi.clear()
            p = s.phi[ticks] = self._compose(s, ticks)
        return p

    def _compose(self, s: _ModeSystem, ticks: int) -> np.ndarray:
        """expm(m * ticks * tick) composed from the cached flows of its
        base-16 digits (d * 16^k ticks, each computed once by
        :func:`expm_balanced`): at most 7 small products instead of a new
        exponential, and exact because the factors commute.  Not cached itself
        (event times are arbitrary: :meth:`_flow` caches the lengths that recur)."""
        p = s.phi.get(ticks)
        if p is not None:
            return p
        n, k = ticks, 0
        while n:
            d = n & 15
            if d:
                key = (k, d)
                f = s.digits.get(key)
                if f is None:
                    f = s.digits[key] = s.expm((d << (4 * k)) * self.tick)
                p = f if p is None else p @ f
            n >>= 4
            k += 1
        return _EYE if p is None else p

    def _digit_integrals(self, s: _ModeSystem, k: int, d: int) -> tuple[np.ndarray, np.ndarray]:
        """(r, G) of one digit's length (d * 16^k ticks): r = e_i' int expm(m t) dt
        and G = int expm(m' t) e_i e_i' expm(m t) dt.  One tick is done by Van
        Loan's block exponential of the balanced matrix (:func:`expm_balanced`,
        checked against scipy's expm in tests/test_plant_stepper.py; over a
        tick its growing block cannot overflow), longer lengths by doubling
        (r(2L) = r + r P, G(2L) = G + P' G P)."""
        hit = s.idigits.get((k, d))
        if hit is not None:
            return hit
        if (k, 1) not in s.idigits:
            if k == 0:
                s.idigits[(0, 1)] = self._tick_integrals(s)
            else:
                r, g = self._digit_integrals(s, k - 1, 1)
                p = self._compose(s, 1 << (4 * (k - 1)))
                for _ in range(4):                 # 16 = 2^4 doublings
                    r, g = r + r @ p, g + p.T @ g @ p
                    p = p @ p
                s.idigits[(k, 1)] = (r, g)
        r1, g1 = s.idigits[(k, 1)]
        p1 = self._compose(s, 1 << (4 * k))
        r, g, p = r1, g1, p1
        for _ in range(d - 1):
            r, g = r + r1 @ p, g + p.T @ g1 @ p
            p = p @ p1
        s.idigits[(k, d)] = (r, g)
        return r, g

    def _tick_integrals(self, s: _ModeSystem) -> tuple[np.ndarray, np.ndarray]:
        tau = self.tick
        n = NZ
        mb, bal = s.mb, s.bal
        cb = np.zeros(n)
        cb[ax.I_] = bal[ax.I_]                   # e_i in balanced coordinates (D c)
        a = np.zeros((2 * n, 2 * n))
        a[:n, :n], a[:n, n:] = mb, np.eye(n)
        ones = np.ones(2 * n)
        hb = expm_balanced(a, ones, tau)[:n, n:]            # int expm(mb t) dt
        v = np.zeros((2 * n, 2 * n))
        v[:n, :n], v[:n, n:], v[n:, n:] = -mb.T, np.outer(cb, cb), mb
        e = expm_balanced(v, ones, tau)
        gb = e[n:, n:].T @ e[:n, n:]
        # back to the state's coordinates: c' expm(Mt) = (D c)' expm(mb t) D^-1
        return (cb @ hb) / bal, gb / bal[:, None] / bal[None, :]

    def _integrals_at(self, s: _ModeSystem, t: float) -> tuple[np.ndarray, np.ndarray]:
        """(r, G) over a flow of length t: whole ticks composed from the digits
        (r(a+b) = r(a) + r(b) P(a), G(a+b) = G(a) + P(a)' G(b) P(a)), the
        sub-tick remainder to first order."""
        n_t = int(t / self.tick)
        rem = t - n_t * self.tick
        hit = s.icache.get(n_t)
        if hit is None:
            p = _EYE
            r = np.zeros(NZ)
            g = np.zeros((NZ, NZ))
            n, k = n_t, 0
            while n:
                d = n & 15
                if d:
                    rd, gd = self._digit_integrals(s, k, d)
                    f = s.digits.get((k, d))
                    if f is None:
                        f = s.digits[(k, d)] = s.expm((d << (4 * k)) * self.tick)
                    r = r + rd @ p
                    g = g + p.T @ gd @ p
                    p = p @ f
                n >>= 4
                k += 1
            hit = (p, r, g)
            if len(s.icache) < 4096:
                s.icache[n_t] = hit
        p, r, g = hit
        if rem > 0.0:
            pi = p[ax.I_]
            r = r + rem * pi
            g = g + rem * np.outer(pi, pi)
        return r, g

    def _accumulate(self, s: _ModeSystem, z: np.ndarray, tau: float) -> None:
        """The current integrals over a flow of length tau from state z.  A
        length met before is done by its (r, G) (:meth:`_integrals_at`,
        cached); a new one (an event's) by carrying the vector through the
        digits (r(a+b) z = r(a) z + r(b) P(a) z, and likewise for G), which
        costs products with a vector instead of matrix products."""
        n_t = int(tau / self.tick)
        if n_t in s.icache or n_t in s.iseen:
            r, g = self._integrals_at(s, tau)
            self.q_i += float(r @ z)
            self.q_i2 += float(z @ g @ z)
            return
        s.iseen.add(n_t)
        rem = tau - n_t * self.tick
        q = q2 = 0.0
        v = z
        n, k = n_t, 0
        while n:
            d = n & 15
            if d:
                rd, gd = self._digit_integrals(s, k, d)
                q += float(rd @ v)
                q2 += float(v @ gd @ v)
                v = self._digit(s, k, d) @ v
            n >>= 4
            k += 1
        if rem > 0.0:
            q += rem * float(v[ax.I_])
            q2 += rem * float(v[ax.I_]) ** 2
        self.q_i += q
        self.q_i2 += q2

    def _digit(self, s: _ModeSystem, k: int, d: int) -> np.ndarray:
        """The flow of d * 16^k ticks, computed once."""
        f = s.digits.get((k, d))
        if f is None:
            f = s.digits[(k, d)] = s.expm((d << (4 * k)) * self.tick)
        return f

    def _state_at(self, s: _ModeSystem, t: float, z: np.ndarray) -> np.ndarray:
        """expm(m t) z for an arbitrary t, by products with the vector: the
        sub-tick remainder (under one 10 ns tick) by a 5th-order Taylor
        series of the balanced matrix, whose norm times a tick is about 1e-2
        for the stiffest mode (183 kHz): truncation below 1e-12; then the
        whole ticks through the digit flows (they commute).  Event location
        runs on it."""
        n = int(t / self.tick)
        rem = t - n * self.tick
        if rem > 0.0:
            u = z / s.bal
            w = u
            for k in (5, 4, 3, 2, 1):
                w = u + (s.mb @ w) * (rem / k)
            z = w * s.bal
        p = s.phi.get(n)
        if p is not None:
            return p @ z
        k = 0
        while n:
            d = n & 15
            if d:
                z = self._digit(s, k, d) @ z
            n >>= 4
            k += 1
        return z

    def _find_event(self, s: _ModeSystem, z0: np.ndarray, z1: np.ndarray,
                    tau: float) -> tuple[float, int, np.ndarray] | None:
        """Earliest guard crossing in (0, tau]: (time, guard index, state)."""
        assert s.gg is not None and s.tol_list is not None
        n = len(s.tol_list)
        v0 = (s.gg @ z0).tolist()    # guards and their time derivatives
        v1 = (s.gg @ z1).tolist()
        brackets: list[tuple[int, float, float]] = []   # guard, bracket end, first guess
        for j in range(n):
            tol = s.tol_list[j]
            g1 = v1[j]
            d0, d1 = v0[n + j] * tau, v1[n + j] * tau
            if g1 < -tol:
                brackets.append((j, tau, tau * _hermite_root(v0[j], d0, g1, d1, 1.0)))
                continue
            if d0 < 0 < d1:          # a minimum inside: does it dip below zero?
                sm = _hermite_min(v0[j], d0, g1, d1)
                if sm is not None:
                    tm = sm * tau
                    if float(s.g[j] @ self._state_at(s, tm, z0)) < -tol:  # type: ignore[index]
                        brackets.append((j, tm, tau * _hermite_root(v0[j], d0, g1, d1, sm)))
        if not brackets:
            return None
        best: tuple[float, int, np.ndarray] | None = None
        for j, hi, guess in brackets:
            t, z = self._locate(s, j, z0, hi, guess)
            if best is None or t < best[0]:
                best = (t, j, z)
        return best

    def _locate(self, s: _ModeSystem, j: int, z0: np.ndarray,
                hi: float, guess: float | None = None) -> tuple[float, np.ndarray]:
        """Crossing time of guard j in (0, hi]: Newton on the exact flow
        (the guard's time derivative is exact, row @ m @ z), kept inside the
        bracket and alternated with bisection, from ``guess`` (the root of
        the guard's cubic Hermite fit) when given.  Stops when the guard is
        within its tolerance below zero or the bracket is below 1 ps; returns
        the time and the state there."""
        row = s.g[j]  # type: ignore[index]
        drow = s.gm[j]  # type: ignore[index]
        tol = float(s.tol[j])  # type: ignore[index]
        lo, glo = 0.0, float(row @ z0)
        if glo <= 0.0:
            # on the surface (a mode just entered there): leaving at once if
            # the guard decreases, else find where it turned positive first
            if float(drow @ z0) < 0.0:
                return 0.0, z0
            lo = 1e-9
            while lo < hi:
                glo = float(row @ self._state_at(s, lo, z0))
                if glo > tol:
                    break
                lo *= 4.0
            else:
                return hi, self._state_at(s, hi, z0)
        if guess is not None and lo < guess < hi:
            # the Hermite root is close: bracket it from above by a hair so
            # Newton lands on the guard's negative side in one or two steps
            zhi, ghi = None, -math.inf
            t = guess
        else:
            zhi = self._state_at(s, hi, z0)
            ghi = float(row @ zhi)
            t = (lo * ghi - hi * glo) / (ghi - glo) if ghi != glo else 0.5 * hi
        g_prev = math.inf
        for _ in range(80):
            if not (lo < t < hi):
                t = 0.5 * (lo + hi)
            zt = self._state_at(s, t, z0)
            gt = float(row @ zt)
            if -tol <= gt <= 0.0:
                return t, zt
            if gt < 0:
                hi, ghi, zhi = t, gt, zt
            else:
                lo, glo = t, gt
            if hi - lo <= 1e-12:
                break
            dg = float(drow @ zt)
            if dg != 0.0 and abs(gt) < 0.5 * g_prev:
                # Newton while it converges; aim a hair past the root, onto
                # the negative side, when coming from above
                t = t - gt / dg
                if gt > 0:
                    t += 1e-3 * abs(gt / dg) + 1e-14
            else:
                t = 0.5 * (lo + hi)      # no progress: bisect the bracket
            g_prev = abs(gt)
        if zhi is None:
            zhi = self._state_at(s, hi, z0)
        return hi, zhi

    def _encode(self, z0: np.ndarray, z1: np.ndarray, t0: float, tau: float,
                out: list[Edge]) -> None:
        """Encoder edges along the cubic Hermite path of the motor angle
        (exact angle and speed at both ends of the step)."""
        if not self.encoder:
            return
        phi0, phi1 = float(z0[ax.PHI_M]), float(z1[ax.PHI_M])
        w0, w1 = float(z0[ax.W_M]), float(z1[ax.W_M])
        enc = self.enc
        u1 = phi1 / enc.rad_per_count + enc.phase_offset_counts
        c1 = math.floor(u1)
        c0 = self.count
        if c1 == c0 and w0 * w1 >= 0:
            return                      # monotonic and no count change
        if w0 * w1 > 0 and abs(c1 - c0) <= 8:
            # monotonic path: solve H(s) = threshold by Newton per edge
            step = 1 if c1 > c0 else -1
            k = 1.0 / enc.rad_per_count
            off = enc.phase_offset_counts
            u0 = phi0 * k + off
            du0, du1 = w0 * tau * k, w1 * tau * k
            a3 = 2 * u0 + du0 - 2 * u1 + du1
            a2 = -3 * u0 - 2 * du0 + 3 * u1 - du1
            c = c0
            sg = 0.0
            ok = True
            while c != c1:
                nxt = c + step
                thr = float(nxt if step > 0 else c)
                sg = max(sg, (thr - u0) / (u1 - u0))
                for _ in range(30):
                    f = ((a3 * sg + a2) * sg + du0) * sg + u0 - thr
                    df = (3 * a3 * sg + 2 * a2) * sg + du0
                    if df * step <= 0:
                        ok = False
                        break
                    ds = f / df
                    sg -= ds
                    if abs(ds) < 1e-13:
                        break
                if not ok or not (0.0 <= sg <= 1.0):
                    ok = False
                    break
                out.append(Edge(t0 + sg * tau, self.index, *pins_of(nxt, enc)))
                c = nxt
            if ok:
                self.count = c1
                return
            del out[len(out) - abs(c - c0):]
        n = max(17, min(4097, 4 * abs(c1 - c0) + 1))
        s = self._s if n == 17 else np.linspace(0.0, 1.0, n)
        ph = hermite(phi0, w0, phi1, w1, tau, s)
        ph[0], ph[-1] = phi0, phi1
        self.count = edges_from_samples(t0 + s * tau, ph, self.index, self.enc, out)

    def advance(self, dt: float, out: list[Edge], t_offset: float = 0.0) -> None:
        """Advance by dt (rounded to ticks) with the pins already set;
        append encoder edges (times offset by ``t_offset``) to ``out``."""
        # round the running total, not each dt, so rounding never accumulates
        self._t_req += dt
        target = round(self._t_req / self.tick)
        q2 = self.q_i2
        start = self._ticks
        if self.timing:
            t = t_offset
            while self._sched and self._sched[0][0] <= target:
                at, pins = self._sched[0]
                self._sched = self._sched[1:]
                if at > self._ticks:
                    t = self._run(at - self._ticks, out, t)
                    self._ticks = at
                self._apply_pins(pins)
            remaining = target - self._ticks
            self._ticks = target
            self._run(remaining, out, t)
        else:
            remaining = target - self._ticks
            self._ticks = target
            self._run(remaining, out, t_offset)
        if self.heats and target > start:
            self._heat((target - start) * self.tick, self.q_i2 - q2)

    #: the winding resistance is rebuilt into the mode matrices when the
    #: temperature has moved it by more than this fraction (0.25 K of copper)
    R_REBUILD_FRAC = 1e-3

    def _heat(self, dt: float, q2: float) -> None:
        """The winding's first-order thermal model over ``dt`` with the
        copper loss of that time (its exact i^2 integral ``q2`` times R(T)),
        held constant over the step: exact for a constant loss."""
        a = self.params
        r = a.resistance_ohm * (1.0 + a.winding_alpha_per_K * self.theta)
        rise = a.winding_thermal_K_per_W * r * q2 / dt
        self.theta = rise + (self.theta - rise) * math.exp(-dt / a.winding_thermal_tau_s)
        r = a.resistance_ohm * (1.0 + a.winding_alpha_per_K * self.theta)
        if abs(r - self._r_wind) > self.R_REBUILD_FRAC * self._r_wind:
            import dataclasses
            self._r_wind = r
            self.c = dataclasses.replace(self.c, R=r + 2.0 * self.bridge.r_on_ohm)
            self._systems = {}
            self._pin_levels = {}

    @property
    def winding_ohm(self) -> float:
        """The winding resistance the plant runs with now (R(T))."""
        return self._r_wind

    def _run(self, remaining: int, out: list[Edge] | None, t: float) -> float:
        """Integrate ``remaining`` ticks with the outputs as they are."""
        while remaining > 0:
            s = self._system()
            k = min(remaining, s.h_ticks)
            remaining -= k
            t = self._chunk(s, k, out, t)
        return t

    def _chunk(self, s: _ModeSystem, k: int, out: list[Edge] | None, t: float) -> float:
        """One chunk of ``k`` ticks from the state in system ``s`` (the
        axis's mode), through every mode switch inside it; encoder edges go
        to ``out`` (None: no edges, and the count is left to the caller)."""
        tau = k * self.tick
        p: np.ndarray | None = self._flow(s, k)
        for _ in range(self.MAX_EVENTS_PER_CHUNK):
            z1 = p @ self.z if p is not None else self._state_at(s, tau, self.z)
            ev = None if s.g is None else self._find_event(s, self.z, z1, tau)
            if ev is None:
                if self.energy:
                    self._accumulate(s, self.z, tau)
                if out is not None:
                    self._encode(self.z, z1, t, tau, out)
                self.z = z1
                t += tau
                break
            te, j, ze = ev
            if self.energy:
                self._accumulate(s, self.z, te)
            if out is not None:
                self._encode(self.z, ze, t, te, out)
            self.z = ze
            t += te
            tau -= te
            self.events += 1
            self.mode = ax.next_mode(self.c, self.z[:ax.N_STATE], self.mode, s.guards[j],
                                     self.e_pos, self.e_neg)
            s = self._system()
            if tau <= 1e-13:
                break
            p = None                     # the rest of the chunk: an arbitrary length
        else:
            raise RuntimeError(f"axis {self.index}: more than {self.MAX_EVENTS_PER_CHUNK} "
                               f"mode switches in one chunk (Zeno?) mode={self.mode}")
        return t

    # ---- many edges at once (the fast path) ------------------------------
    #: most chunks integrated before their guards are checked together
    #: (run_pins); fewer after a mode switch, twice as many after none
    BATCH = 256
    _batch = 8

    def run_pins(self, changes: Sequence[tuple[int, Pins]], ticks: int) -> None:
        """Advance ``ticks`` ticks while the bridge's inputs change to each
        ``(offset, pins)`` of ``changes`` (offsets in ticks from now, sorted,
        below ``ticks``): the same flow as :meth:`set_pins` and
        :meth:`advance` at every change, for a caller that reads the count
        only between calls.  It makes no encoder edges (the count is the
        angle's at the end, as the edges would have left it), checks the
        guards of many chunks in one product (:meth:`_run_batch`) and heats
        the winding once per call."""
        start = self._ticks
        end = start + ticks
        q2 = self.q_i2
        self._run_batch(self._segments(changes, start, end))
        self._ticks = end
        self._t_req = end * self.tick
        self.count = count_of(float(self.z[ax.PHI_M]), self.enc)
        if self.heats and ticks > 0:
            self._heat(ticks * self.tick, self.q_i2 - q2)

    def _segments(self, changes: Sequence[tuple[int, Pins]], start: int, end: int) -> list[tuple[int, Pins]]:
        """(ticks, output pins) from ``start`` to ``end``: the commanded
        changes, through the bridge's delays and minimum pulse when it has
        them (:meth:`_command`, which this drives as :meth:`advance` does).
        A change of zero length is kept: the outputs pass through it."""
        segs: list[tuple[int, Pins]] = []
        cur, shown = start, self.pins

        def show_until(t: int) -> None:
            nonlocal cur, shown
            while self._sched and self._sched[0][0] <= t:
                at, pins = self._sched[0]
                self._sched = self._sched[1:]
                segs.append((max(0, at - cur), shown))
                cur, shown = max(cur, at), pins

        for off, pins in changes:
            at = start + off
            if self.timing:
                show_until(at)
                self._ticks = at
                self._command(pins)
            else:
                segs.append((at - cur, shown))
                cur, shown = at, pins
        if self.timing:
            show_until(end)
        segs.append((end - cur, shown))
        return segs

    def _run_batch(self, segs: list[tuple[int, Pins]]) -> None:
        """Integrate the output segments: up to :attr:`_batch` chunks ahead
        by their cached flows (a segment's whole chunks in one product with
        the stacked powers of the chunk's flow, :meth:`_powers`), then the
        guards of all of them in one product (the tests of
        :meth:`_find_event`, vectorised, :meth:`_flags`); the chunks before
        the first that may hold a mode switch are taken, that one is
        integrated by :meth:`_chunk` (the exact event handling), and the
        batch goes on from there (from its next chunk unchanged if no switch
        happened).  The current integrals of the taken chunks are summed in
        one product too (:meth:`_take`)."""
        n_state = ax.N_STATE
        i, left, entered = 0, segs[0][0], False      # where the axis stands
        batch = self._batch
        while True:
            # 1. integrate ahead: pieces of m chunks of k ticks in one system
            z, mode, pins, e_pos, e_neg = self.z, self.mode, self.pins, self.e_pos, self.e_neg
            si, sl, ent = i, left, entered
            pieces: list[tuple[int, int, _ModeSystem, int, Pins, int, int]] = []  # first, m, s, k, pins, seg, left
            blocks = [z[None, :]]
            n = 0
            s = self._system()
            while n < batch:
                if not ent:
                    ent = True
                    p = segs[si][1]
                    if p != pins:
                        pins = p
                        e_pos, e_neg = self._levels(pins)
                        se = ax.elec_mode(self.c, z[:n_state], e_pos, e_neg)
                        if se != mode.se:
                            mode = mode._replace(se=se)
                        s = self._system((mode, e_pos, e_neg))
                if sl == 0:
                    if si + 1 == len(segs):
                        break
                    si, sl, ent = si + 1, segs[si + 1][0], False
                    continue
                h = s.h_ticks
                if sl >= h:
                    k, m = h, min(sl // h, batch - n)
                    zb = self._powers(s, m) @ z
                else:
                    k, m = sl, 1
                    zb = (self._flow(s, sl) @ z)[None, :]
                pieces.append((n, m, s, k, pins, si, sl))
                blocks.append(zb)
                z = zb[-1]
                sl -= m * k
                n += m
            if n == 0:
                self.mode, self.pins, self.e_pos, self.e_neg = mode, pins, e_pos, e_neg
                return
            # 2. which chunks may hold a switch
            zz = np.concatenate(blocks)
            flagged = self._flags(pieces, zz)
            # 3. take the chunks before it; the flagged one exactly
            done = 0
            restart = False
            firsts = [pc[0] for pc in pieces]
            for j in flagged + [n]:
                if j > done:
                    self._take(pieces, zz, done, j)
                    done = j
                if j == n:
                    break
                first, m, s, k, p, ri, rl = pieces[bisect.bisect_right(firsts, j) - 1]
                self.z = zz[j]
                self.mode, self.pins, self.e_pos, self.e_neg = s.mode, p, s.e_pos, s.e_neg
                ev = self.events
                self._chunk(s, k, None, 0.0)
                done = j + 1
                i, left, entered = ri, rl - (j - first + 1) * k, True
                if self.events != ev:
                    restart = True       # the mode changed: integrate ahead anew from here
                    break
            # as many chunks ahead as there are between switches, within bounds
            batch = max(4, batch // 2) if restart else min(self.BATCH, 2 * batch)
            self._batch = batch
            if not restart:
                first, m, s, k, p, ri, rl = pieces[-1]
                i, left, entered = ri, rl - m * k, True
                self.z = zz[-1]
                self.mode, self.pins, self.e_pos, self.e_neg = s.mode, p, s.e_pos, s.e_neg
                if ent and sl == 0 and si + 1 == len(segs):    # the segments are done
                    self.mode, self.pins, self.e_pos, self.e_neg = mode, pins, e_pos, e_neg
                    return

    def _levels(self, pins: Pins) -> tuple[float, float]:
        """(e_pos, e_neg) the bridge presents with these output pins (as
        :meth:`_apply_pins` sets them), per pins once."""
        lv = self._pin_levels.get(pins)
        if lv is None:
            lv = self._pin_levels[pins] = ax.terminal_levels(self.c, *armature_voltages(pins, self.bridge))
        return lv

    def _powers(self, s: _ModeSystem, m: int) -> np.ndarray:
        """The flows of 1..m whole chunks of ``s.h_ticks`` (m x 14 x 14), built once."""
        pw = s.hpow
        if pw is None or len(pw) < m:
            f = self._flow(s, s.h_ticks)
            out = [f] if pw is None else list(pw)
            while len(out) < self.BATCH:
                out.append(f @ out[-1])
            pw = s.hpow = np.array(out)
        return pw[:m]

    def _flags(self, pieces: list, zz: np.ndarray) -> list[int]:
        """Indices of the chunks whose guards cross, or may dip, below zero
        (the tests of :meth:`_find_event`, on all chunks at once)."""
        by: dict[int, tuple[_ModeSystem, list]] = {}
        for pc in pieces:
            if pc[2].g is not None:
                by.setdefault(id(pc[2]), (pc[2], []))[1].append(pc)
        out: list[int] = []
        for s, pcs in by.values():
            n = len(s.tol_list)
            rows_l: list[int] = []
            ticks_l: list[int] = []
            for first, m, _, k, *_ in pcs:
                rows_l.extend(range(first, first + m))
                ticks_l.extend([k] * m)
            ia = np.array(rows_l)
            tau = np.array(ticks_l, float)[:, None] * self.tick
            w = zz @ s.gg.T              # every state once: a chunk's start is the one before's end
            v0, v1 = w[ia], w[ia + 1]
            g0, g1 = v0[:, :n], v1[:, :n]
            d0, d1 = v0[:, n:] * tau, v1[:, n:] * tau
            hit = (g1 < -s.tol).any(axis=1)
            # a dip needs the slope to turn, and the cubic can fall at most
            # 4/27 (|d0| + |d1|) below the lower end (Hermite basis bounds)
            dip = (d0 < 0) & (d1 > 0) & (np.minimum(g0, g1) < (4 / 27) * (d1 - d0))
            rows = dip.any(axis=1)
            if rows.any():
                hit[rows] |= (dip[rows] & _hermite_dips(g0[rows], d0[rows], g1[rows], d1[rows])).any(axis=1)
            out.extend(ia[hit].tolist())
        out.sort()
        return out

    def _take(self, pieces: list, zz: np.ndarray, a: int, b: int) -> None:
        """Chunks a..b-1 hold no switch: their current integrals."""
        if not self.energy:
            return
        by: dict[tuple[int, int], tuple[_ModeSystem, int, list[int]]] = {}
        for first, m, s, k, *_ in pieces:
            lo, hi = max(a, first), min(b, first + m)
            if lo < hi:
                by.setdefault((id(s), k), (s, k, []))[2].extend(range(lo, hi))
        for s, k, rows in by.values():
            r, g = self._integrals_at(s, k * self.tick)
            z0 = zz[rows]
            self.q_i += float((z0 @ r).sum())
            self.q_i2 += float(((z0 @ g) * z0).sum())


def _driving(p: Pins) -> bool:
    """Whether the pins switch a high side on (a driving phase)."""
    return bool((p[0] and p[2]) or (p[1] and p[3]))


def expm_balanced(mb: np.ndarray, bal: np.ndarray, tau: float) -> np.ndarray:
    """expm(M tau) with M = diag(bal) mb diag(bal)^-1: Taylor series of
    degree 10 on tau mb scaled to a 1-norm <= 1/4 (truncation < 1e-14), then
    repeated squaring.  scipy.linalg.expm gives the same result to 2e-11
    relative (checked in tests/test_plant_stepper.py) but takes milliseconds
    on these stiff, badly scaled matrices; this takes ~0.1 ms."""
    a = mb * tau
    nrm = float(np.abs(a).sum(axis=0).max())
    sq = max(0, math.ceil(math.log2(nrm / 0.25))) if nrm > 0.25 else 0
    a = a * (0.5**sq)
    eye = _EYE if len(a) == NZ else np.eye(len(a))
    e = eye + a / 10.0
    for k in range(9, 0, -1):
        e = eye + (a @ e) / k
    for _ in range(sq):
        e = e @ e
    return e * bal[:, None] / bal[None, :]


_EYE = np.eye(NZ)


def _hermite_root(g0: float, d0: float, g1: float, d1: float, s_hi: float) -> float:
    """First zero in (0, s_hi] of the cubic Hermite through (g0, d0), (g1, d1)
    (derivatives scaled by the step), with g0 > 0 and the cubic negative at
    s_hi: bisection, then Newton polishing.  A first guess for _locate."""
    a = 2 * g0 + d0 - 2 * g1 + d1
    b = -3 * g0 - 2 * d0 + 3 * g1 - d1
    lo, hi = 0.0, s_hi
    for _ in range(30):
        m = 0.5 * (lo + hi)
        if ((a * m + b) * m + d0) * m + g0 > 0:
            lo = m
        else:
            hi = m
    return 0.5 * (lo + hi)


def _hermite_min(g0: float, d0: float, g1: float, d1: float) -> float | None:
    """Location in (0, 1) of the minimum of the cubic Hermite through
    (g0, d0), (g1, d1) (derivatives already scaled by the step), if it dips
    below zero there."""
    # p(s) = a s^3 + b s^2 + d0 s + g0
    a = 2 * g0 + d0 - 2 * g1 + d1
    b = -3 * g0 - 2 * d0 + 3 * g1 - d1
    # p'(s) = 3a s^2 + 2b s + d0 = 0
    roots: list[float] = []
    if abs(a) < 1e-300:
        if b != 0:
            roots = [-d0 / (2 * b)]
    else:
        disc = b * b - 3 * a * d0
        if disc >= 0:
            r = math.sqrt(disc)
            roots = [(-b - r) / (3 * a), (-b + r) / (3 * a)]
    best = None
    for sr in roots:
        if 0 < sr < 1:
            v = ((a * sr + b) * sr + d0) * sr + g0
            if v < 0 and (best is None or v < best[1]):
                best = (sr, v)
    return None if best is None else best[0]


def _hermite_dips(g0: np.ndarray, d0: np.ndarray, g1: np.ndarray, d1: np.ndarray) -> np.ndarray:
    """Elementwise: whether the cubic Hermite through (g0, d0), (g1, d1) has
    a stationary point in (0, 1) below zero (:func:`_hermite_min`'s test)."""
    a = 2 * g0 + d0 - 2 * g1 + d1
    b = -3 * g0 - 2 * d0 + 3 * g1 - d1
    out = np.zeros(g0.shape, bool)
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        small = np.abs(a) < 1e-300
        r = np.sqrt(b * b - 3 * a * d0)
        for sr, valid in (((-b - r) / (3 * a), ~small), ((-b + r) / (3 * a), ~small), (-d0 / (2 * b), small)):
            v = ((a * sr + b) * sr + d0) * sr + g0
            out |= valid & (sr > 0) & (sr < 1) & (v < 0)
    return out


class TwoAxisPlant:
    """The two-axis stage for co-simulation (axis 0 = x, axis 1 = z)."""

    def __init__(self, params: PlantParams | None = None, h_max_s: float = 1e-3,
                 tick_s: float = 1e-8, glitch_rate_hz: float = 0.0,
                 glitch_width_s: float = 200e-9, seed: int = 0, energy: bool = False) -> None:
        self.params = params or load_params()
        self.axes = [FastAxis(a, self.params, i, h_max_s, tick_s, energy=energy)
                     for i, a in enumerate(self.params.axes)]
        self.t = 0.0
        self.glitch_rate_hz = glitch_rate_hz
        self.glitch_width_s = glitch_width_s
        self.seed = seed              # the encoder glitches' generator: the same seed, the same run
        self._rng = random.Random(seed)
        self._pin_state = {i: (0, 0, 0) for i in range(len(self.axes))}
        for i, a in enumerate(self.axes):
            self._pin_state[i] = pins_of(a.count, self.params.encoder)

    def advance(self, dt: float, pins: Sequence[Pins]) -> list[Edge]:
        """Hold ``pins`` (one Pins per axis) for ``dt`` seconds.  Returns the
        encoder edges of the step in time order: (t, axis, a, b, z) with t in
        seconds after the start of this call; each edge gives the new levels
        of that axis's A, B and Z pins."""
        out: list[Edge] = []
        for a, p in zip(self.axes, pins):
            a.set_pins(p)
            a.advance(dt, out)
        if len(self.axes) > 1 and out:
            out.sort(key=lambda e: e.t)
        if self.glitch_rate_hz > 0:
            out = add_glitches(out, 0.0, dt, self.glitch_rate_hz, self.glitch_width_s,
                               self._pin_state, self._rng)
        self.t += dt
        return out

    def run_pins(self, ticks: int, changes: Sequence[Sequence[tuple[int, Pins]]]) -> None:
        """Advance ``ticks`` ticks (``tick_s`` each) with each axis's bridge
        inputs changing as its list of ``(offset in ticks, pins)`` says
        (:meth:`FastAxis.run_pins`): no encoder edges, the counts read
        between calls; for a caller that knows every pin change of a
        control period in advance (the fast path)."""
        for a, ch in zip(self.axes, changes):
            a.run_pins(ch, ticks)
        self.t += ticks * self.axes[0].tick

    def snapshot(self) -> tuple:
        """The plant's whole state (both axes, clock, glitch generator), for a
        co-simulation that advances speculatively and may have to undo."""
        return self.t, dict(self._pin_state), self._rng.getstate(), tuple(a.snapshot() for a in self.axes)

    def restore(self, snap: tuple) -> None:
        self.t, pin_state, rng, axes = snap
        self._pin_state = dict(pin_state)
        self._rng.setstate(rng)
        for a, s in zip(self.axes, axes):
            a.restore(s)

    def advance_volts(self, dt: float, volts: Sequence[float]) -> None:
        """Hold ideal armature voltages (one per axis) for ``dt`` seconds (the
        averaged model; no encoder edges are produced)."""
        for a, v in zip(self.axes, volts):
            a.set_voltage(v)
            a.advance(dt, [])
        self.t += dt

    # ---- accessors (SI unless the name says otherwise) -------------------
    def motor_angle(self, axis: int) -> float:
        return float(self.axes[axis].z[ax.PHI_M])

    def motor_speed(self, axis: int) -> float:
        return float(self.axes[axis].z[ax.W_M])

    def screw_angle(self, axis: int) -> float:
        return float(self.axes[axis].z[ax.PHI_S])

    def screw_speed(self, axis: int) -> float:
        return float(self.axes[axis].z[ax.W_S])

    def table_mm(self, axis: int) -> float:
        return 1e3 * float(self.axes[axis].z[ax.CHI_L])

    def table_speed_mm_s(self, axis: int) -> float:
        return 1e3 * float(self.axes[axis].z[ax.V_L])

    def current(self, axis: int) -> float:
        return float(self.axes[axis].z[ax.I_])

    def is_currents(self, axis: int) -> tuple[float, float]:
        a = self.axes[axis]
        if not isinstance(a.pins, Pins):
            return 0.0, 0.0          # an ideal voltage source: no bridge to sense
        return is_currents(a.pins, float(a.z[ax.I_]), self.params.bridge)

    def count(self, axis: int) -> int:
        return self.axes[axis].count

    def table_counts(self, axis: int) -> float:
        """The table's position in encoder counts (chi_l through the nominal
        lead and gear ratio, as the motor-side encoder would count a rigid
        drivetrain): the error at the table is the target less this, beside
        the encoder's target less :meth:`count`.  They differ by the
        drivetrain's deflection and the gear backlash, which the encoder
        cannot see."""
        a = self.axes[axis]
        return float(a.z[ax.CHI_L]) / a.c.rn * a.c.G / self.params.encoder.rad_per_count

    def charge(self, axis: int) -> float:
        """Integral of the armature current since the start, A s (energy=True)."""
        return self.axes[axis].q_i

    def current_sq_integral(self, axis: int) -> float:
        """Integral of the armature current squared since the start, A^2 s
        (energy=True): times the winding resistance, the copper loss in J."""
        return self.axes[axis].q_i2

    def state(self, axis: int) -> np.ndarray:
        return self.axes[axis].x.copy()
