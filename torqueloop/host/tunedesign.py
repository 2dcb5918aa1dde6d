# SPDX-License-Identifier: MIT
"""Gains from an identified axis: the design behind ``torqueloop tune``.

The identified axis (the plant file's ``[identifiable.<axis>]`` keys, from
``torqueloop identify`` or ``plant export``) is, in the counts domain of
the firmware's law (docs/firmware.md, "Control"),

    speed   w' = (K (V - V_f(sgn w)) - w) / tau          (rad/s at the motor, V the bridge's mean volts)
    counts  theta' = c w,  c = counts per motor radian
    bridge  V = V_s duty / M,  duty = PW0 + |u| (M - PW0) / M   (eq. 1, u the command in PWM steps)

With PW0 at the friction voltage (:meth:`AxisModel.pw0`, :meth:`AxisModel.fc`)
the friction cancels while the rotor slides, and the loop sees the linear plant  P(s) = Kc / (s (tau s + 1)),
Kc = c K V_s (M - PW0) / M^2  (counts/s per PWM step).  The law is
u = Kp e - Kd v + I, I_k = I_{k-1} + Ki T e_k (derivative on the measured
speed, so no zero from it).  Poles are placed in continuous time (a pair
at wn with damping zeta; PID adds a real pole at alpha wn) and the design is
then checked where it runs: the exact zero-order-hold discretisation at the
control period T, its closed-loop poles and its gain and phase margins with
the loop broken at the plant input.

What the linear design cannot see, stiction, is compensated and sized
separately: for a PD the firmware adds FC_POS / FC_NEG steps to a command
that way, which lifts its smallest duty from PW0 to the direction's own
sliding friction voltage (a PID's integral holds the difference between the
directions, :meth:`AxisModel.fc`); what remains is the breakaway beyond it
(the dead zone, as identified at the carrier): a PD holds anywhere within
e_db = (breakaway - PW0 - FC, in steps) / Kp of the target; the design
raises wn until e_db is within the wish's tolerance, or says it cannot at
this control period (then PID, whose integral walks the command to the
breakaway).  :func:`predict` runs the nonlinear design model (saturation,
the eq. 1 map, FC per direction, Coulomb and breakaway friction per
direction, the integrator held while saturated as control.c holds it and
within the hunting guard's zone) to give the step
metrics the design expects; ``tune --verify`` measures them on the board
image in the loop, which is the check that can disagree.
"""

from __future__ import annotations

import cmath
import math
from dataclasses import dataclass, replace

import numpy as np

from torqueloop.spec.metrics import StepMetrics, step_metrics
from torqueloop.spec.system import SYSTEM

#: ratio of the control rate to the loop's natural frequency the design keeps (wn T <= this)
MAX_WN_T = 0.15
#: the hunting guard of a PID: the integral frozen within one count of the target, the encoder's
#: resolution (no smaller error can be seen, and a rotor stuck one count off winds no command up)
IZONE_COUNTS = 1.0
#: settled means within this many counts of the target (beside the 2 % band of report.json's arms)
TIGHT_BAND_COUNTS = 2.0
#: the trapezoid the feed-forward is verified on (:func:`verify_profile`): its top speed takes this share
#: of the command through the velocity feed-forward, its acceleration this share through the
#: acceleration feed-forward; the rest is the feedback's
VERIFY_VMAX_SHARE, VERIFY_AMAX_SHARE = 0.5, 0.25


@dataclass(frozen=True)
class AxisModel:
    """The identified axis in the units the design works in."""

    speed_gain: float          # K, rad/s per V (motor)
    tau: float                 # s
    friction_v: tuple[float, float]      # V_f per direction (+, -), volts
    breakaway_pct: tuple[float, float]   # dead zone per direction, % of duty
    supply_v: float = 12.0
    counts_per_motor_rad: float = SYSTEM.counts_per_motor_rev / (2 * math.pi)
    full: int = SYSTEM.pwm_full

    @classmethod
    def from_identified(cls, d: dict[str, float], supply_v: float = 12.0) -> "AxisModel":
        return cls(d["speed_gain_rad_per_s_per_v"], d["time_constant_s"],
                   (d["friction_v_pos"], d["friction_v_neg"]),
                   (d["dead_zone_pos_pct"], d["dead_zone_neg_pct"]), supply_v)

    def pw0(self) -> int:
        """Dead-zone compensation in ticks (one PW0 per axis in the firmware):
        the smaller direction's sliding friction voltage, rounded down, so that
        it over-drives neither direction (an over-compensated rotor creeps past
        the target and hunts there: on the scaled lab plant's z axis PW0 at the
        mean of the directions, one tick more, kept the tuned PID between -3
        and +3 counts at 4 s, the smaller settled it into +-2 counts at 2.6 s)."""
        vf = max(0.0, min(self.friction_v))
        return min(self.full - 1, math.floor(vf / self.supply_v * self.full))

    def fc(self, pw0: int, law: str = "pid") -> tuple[int, int]:
        """FC_POS, FC_NEG: per direction, the PWM steps beyond ``pw0`` that bring
        the smallest command's duty to that direction's sliding friction voltage,
        PW0+- = PW0 + FC (M - PW0) / M (protocol.toml): eq. (1) with a PW0 per
        direction.  For a PD only, which has nothing else to meet a difference
        between the directions.  An encoder cannot tell a direction-dependent
        friction from a constant load (z's gravity), and a load stays at rest,
        where the relay FC is would flip with the command's sign: a PID's
        integral holds it instead (on the scaled lab plant's z axis FC_POS 2
        kept the tuned PID hunting between -2 and -3 counts for seconds; 0
        settled it into +-2 counts at 2.6 s).  Never up to the dead zone (the
        breakaway) either: that over-drives a rotor once it slides, and near
        the target every kick moves it several counts."""
        span = self.full - pw0
        if law == "pid" or span <= 0:
            return (0, 0)
        return tuple(max(0, min(self.full, round((v / self.supply_v * self.full - pw0) * self.full / span)))
                     for v in self.friction_v)   # type: ignore[return-value]

    def kc(self, pw0: int) -> float:
        """Counts/s per PWM step of the compensated, sliding plant."""
        return self.counts_per_motor_rad * self.speed_gain * self.supply_v * (self.full - pw0) / self.full**2

    def breakaway_steps(self, pw0: int, fc: tuple[int, int] = (0, 0)) -> float:
        """Command (steps) beyond PW0 and the direction's FC that breaks the rotor away, the larger direction."""
        span = (self.full - pw0) / self.full
        return max(0.0, *((dz / 100 * self.full - pw0) / span - f for dz, f in zip(self.breakaway_pct, fc)))


@dataclass(frozen=True)
class Wish:
    settling_s: float = 0.5          # 2 % band
    overshoot_pct: float = 2.0
    tolerance_counts: float = 2.0    # where a PD may stick: |e| at rest
    law: str = "pid"                 # "pd" or "pid"
    period_s: float = 1e-3           # control period
    cmd_limit: int = SYSTEM.pwm_full


@dataclass(frozen=True)
class Design:
    law: str
    kp: float                  # PWM steps per count
    kd: float                  # PWM steps per count/s
    ki: float                  # PWM steps per count s
    pw0: int                   # ticks
    wn: float
    zeta: float
    period_s: float
    gain_margin_db: float
    phase_margin_deg: float
    poles_z: tuple[complex, ...]
    stick_band_counts: float   # e_db of a PD (0 for PID: the integral breaks away)
    notes: tuple[str, ...]
    fc: tuple[int, int] = (0, 0)   # FC_POS, FC_NEG: PWM steps, the dead zone beyond PW0 per direction
    izone_counts: float = 0.0      # the hunting guard: the integral frozen while |e| is within it
    alpha: float = 0.0             # PID: the real pole at alpha wn
    kvff: float = 0.0              # velocity feed-forward, PWM steps per count/s of the profile's speed
    kaff: float = 0.0              # acceleration feed-forward, PWM steps per count/s^2 of the profile's

    def q16(self) -> dict[str, int]:
        """The firmware's raw gains (KP_Q16, KD_Q16, KI_Q16)."""
        return {"KP_Q16": round(self.kp * 65536), "KD_Q16": round(self.kd * 65536), "KI_Q16": round(self.ki * 65536)}

    def compensation(self) -> dict[str, int]:
        """The firmware's friction compensation beyond PW0 (FC_POS, FC_NEG, IZONE_Q16)."""
        return {"FC_POS": self.fc[0], "FC_NEG": self.fc[1], "IZONE_Q16": round(self.izone_counts * 65536)}

    def feedforward(self) -> dict[str, int]:
        """The firmware's feed-forward on a trapezoid move (KVFF_Q16, KAFF_Q16)."""
        return {"KVFF_Q16": round(self.kvff * 65536), "KAFF_Q16": round(self.kaff * 65536)}


def feedforward(m: AxisModel, pw0: int, kd: float) -> tuple[float, float]:
    """Kvff, Kaff (PWM steps per count/s, per count/s^2): what makes the loop follow a
    profile (v, a) with no error.  The compensated, sliding plant (:meth:`AxisModel.kc`: the
    identified speed gain and time constant through eq. (1) and PW0) needs u = v / Kc + tau a / Kc,
    and the law's D term, on the measured speed, takes Kd v from it: Kvff = 1 / Kc + Kd (the
    steady-speed relation), Kaff = tau / Kc (the inertia, as the time constant carries it).
    The friction is PW0's and the integral's."""
    kc = m.kc(pw0)
    return 1.0 / kc + kd, m.tau / kc


def verify_profile(m: AxisModel, d: Design, cmd_limit: int = SYSTEM.pwm_full) -> tuple[int, int]:
    """VMAX (counts/s) and AMAX (counts/s^2) of the trapezoid the feed-forward is verified on:
    the fastest whose feed-forward keeps within VERIFY_VMAX_SHARE and VERIFY_AMAX_SHARE of the
    command (the axis's, with or without the feed-forward set)."""
    kvff, kaff = feedforward(m, d.pw0, 0.0)      # the plant's share (the D term's is the feedback's)
    return (max(1, math.floor(VERIFY_VMAX_SHARE * cmd_limit / kvff)),
            max(1, math.floor(VERIFY_AMAX_SHARE * cmd_limit / kaff)))


def zeta_for_overshoot(pct: float) -> float:
    """Damping of a second-order pair with that overshoot (at least 0.7)."""
    if pct <= 0:
        return 1.0
    ln = math.log(pct / 100)
    return max(0.7, -ln / math.sqrt(math.pi**2 + ln**2))


def discrete_plant(kc: float, tau: float, t: float) -> tuple[np.ndarray, np.ndarray]:
    """Exact ZOH of x = [counts, counts/s], x' = [[0, 1], [0, -1/tau]] x + [0, kc / tau] u."""
    e = math.exp(-t / tau)
    ad = np.array([[1.0, tau * (1 - e)], [0.0, e]])
    bd = kc * np.array([t - tau * (1 - e), 1 - e])
    return ad, bd


def closed_loop(ad: np.ndarray, bd: np.ndarray, kp: float, kd: float, ki: float, t: float) -> np.ndarray:
    """The regulation loop of control.c's law in the state [counts, counts/s, I_{k-1}]."""
    kpi = kp + ki * t
    m = np.zeros((3, 3))
    m[:2, :2] = ad - np.outer(bd, [kpi, kd])
    m[:2, 2] = bd
    m[2, :] = [-ki * t, 0.0, 1.0]
    return m if ki else m[:2, :2]


def margins(ad: np.ndarray, bd: np.ndarray, kp: float, kd: float, ki: float, t: float) -> tuple[float, float]:
    """Gain margin (dB) and phase margin (degrees) of the loop broken at the
    plant input: L(z) = C(z) (zI - Ad)^-1 Bd, C the law on [counts, counts/s]
    (the phase margin at the gain crossover of L; the gain margin as the
    factor on every gain that makes the closed loop unstable)."""
    ws = np.geomspace(1e-3, math.pi / t, 4000)
    ls = []
    for w in ws:
        z = cmath.exp(1j * w * t)
        x = np.linalg.solve(z * np.eye(2) - ad, bd)          # states per unit input
        integ = ki * t * z / (z - 1)                           # I_k = I_{k-1} + Ki T e_k
        ls.append((kp + integ) * x[0] + kd * x[1])
    ls = np.array(ls)
    mag, ph = np.abs(ls), np.unwrap(np.angle(ls))
    cross = np.nonzero(np.diff(np.sign(mag - 1.0)))[0]
    pm = math.inf
    for i in cross:
        pm = min(pm, (math.degrees(ph[i]) + 180.0) % 360.0)
    # gain margin: the factor on all gains at which a closed-loop pole reaches the unit circle
    # (bisection on the exact discrete loop; the phase reaches -180 degrees at Nyquist itself here,
    # where a frequency sweep cannot find the crossing reliably)
    def unstable(g: float) -> bool:
        return max(abs(np.linalg.eigvals(closed_loop(ad, bd, g * kp, g * kd, g * ki, t)))) >= 1.0

    gm = math.inf
    if unstable(1.0):
        gm = -math.inf
    elif unstable(1e6):
        lo, hi = 1.0, 1e6
        while hi / lo > 1.0001:
            mid = math.sqrt(lo * hi)
            lo, hi = (lo, mid) if unstable(mid) else (mid, hi)
        gm = 20 * math.log10(hi)
    return gm, pm


def _gains(law: str, kc: float, tau: float, wn: float, zeta: float, alpha: float) -> tuple[float, float, float]:
    if law == "pd":
        kp = wn**2 * tau / kc
        kd = max(0.0, (2 * zeta * wn * tau - 1) / kc)
        return kp, kd, 0.0
    kd = max(0.0, ((2 * zeta + alpha) * wn * tau - 1) / kc)
    kp = (wn**2 + 2 * zeta * alpha * wn**2) * tau / kc
    ki = alpha * wn**3 * tau / kc
    return kp, kd, ki


def design(m: AxisModel, w: Wish, alpha: float = 1.0, zeta: float | None = None) -> Design:
    """The design for the wish; ``zeta`` (at least the wish's) overrides the
    damping the overshoot limit gives (wn follows: 4.6 / (zeta settling))."""
    if w.law not in ("pd", "pid"):
        raise ValueError(f"law {w.law!r}: tune designs pd or pid")
    least = zeta_for_overshoot(w.overshoot_pct) if w.law == "pd" else max(0.9, zeta_for_overshoot(w.overshoot_pct))
    zeta = least if zeta is None else max(least, zeta)
    pw0 = m.pw0()
    fc = m.fc(pw0, w.law)
    kc = m.kc(pw0)
    wn = 4.6 / (zeta * w.settling_s)
    notes = []
    wn_cap = MAX_WN_T / w.period_s
    stick = 0.0
    if w.law == "pd":
        need = m.breakaway_steps(pw0, fc) / w.tolerance_counts      # Kp that breaks away within the tolerance
        wn_stick = math.sqrt(need * kc / m.tau)
        if wn_stick > wn:
            notes.append(f"wn raised from {wn:.1f} to {wn_stick:.1f} rad/s so that the breakaway is reached "
                         f"within {w.tolerance_counts:g} counts")
            wn = wn_stick
    if wn > wn_cap:
        notes.append(f"wn capped at {wn_cap:.1f} rad/s by the control period ({w.period_s * 1e3:g} ms): "
                     "shorten the period for a faster loop")
        wn = wn_cap
    kp, kd, ki = _gains(w.law, kc, m.tau, wn, zeta, alpha)
    if w.law == "pd":
        stick = m.breakaway_steps(pw0, fc) / kp
    ad, bd = discrete_plant(kc, m.tau, w.period_s)
    poles = tuple(complex(p) for p in np.linalg.eigvals(closed_loop(ad, bd, kp, kd, ki, w.period_s)))
    if max(abs(p) for p in poles) >= 1:
        notes.append("UNSTABLE at this control period: a closed-loop pole lies outside the unit circle")
    gm, pm = margins(ad, bd, kp, kd, ki, w.period_s)
    izone = IZONE_COUNTS if w.law == "pid" and w.tolerance_counts >= IZONE_COUNTS else 0.0
    kvff, kaff = feedforward(m, pw0, kd)
    return Design(w.law, kp, kd, ki, pw0, wn, zeta, w.period_s, gm, pm, poles, stick, tuple(notes), fc, izone,
                  alpha if w.law == "pid" else 0.0, kvff, kaff)


def trapezoid(distance: float, vmax: float, amax: float, t_ctl: float, n: int) -> np.ndarray:
    """The design model's trapezoid set-point, per control sample: rows (set-point counts,
    speed counts/s, acceleration counts/s^2).  As the firmware's profile (docs/firmware.md,
    "Control", step 4): the speed rises by amax T^2 per sample up to vmax T and never beyond
    the speed from which braking by amax T^2 per sample stops at the target, the last step
    lands on it (in real numbers; the firmware's is in q16 and bit for bit the oracle's)."""
    a, vm = amax * t_ctl**2, vmax * t_ctl
    out = np.zeros((n, 3))
    sp, v, sgn, d0 = 0.0, 0.0, math.copysign(1.0, distance), abs(distance)
    for k in range(n):
        d = d0 - sp
        # D(v) = v + (v - a) + ... ~ v^2 / (2a) + v / 2 <= d
        allow = a * (-0.5 + math.sqrt(0.25 + 2 * d / a)) if d > 0 else 0.0
        vs = min(v + a, vm, allow)
        if vs >= d:
            sp, acc, v = d0, 0.0, 0.0
        else:
            acc, v = vs - v, vs
            sp += v
        out[k] = (sgn * sp, sgn * v / t_ctl, sgn * acc / t_ctl**2)
    return out


def predict(m: AxisModel, d: Design, step_counts: float, t_end_s: float, cmd_limit: int = SYSTEM.pwm_full,
            direction_first: int = 1) -> tuple[np.ndarray, np.ndarray, StepMetrics]:
    """The design model's step response (nonlinear: saturation, the eq. 1
    map, sliding and breakaway friction, the integrator held while
    saturated toward the error): times (s), positions (counts), metrics."""
    t_arr, x_arr, _ = simulate(m, d, np.full((round(t_end_s / d.period_s), 3), [step_counts, 0.0, 0.0]), cmd_limit)
    return t_arr, x_arr, step_metrics(t_arr, x_arr, step_counts)


def predict_following(m: AxisModel, d: Design, distance: float, vmax: float, amax: float, t_end_s: float,
                      cmd_limit: int = SYSTEM.pwm_full, feedforward: bool = True
                      ) -> tuple[float, np.ndarray, np.ndarray]:
    """The design model on a trapezoid move, with the design's feed-forward or (``feedforward``
    False) without: its peak following error (counts, |set-point - position|), times (s) and
    positions (counts)."""
    sp = trapezoid(distance, vmax, amax, d.period_s, round(t_end_s / d.period_s))
    ts, xs, _ = simulate(m, d if feedforward else replace(d, kvff=0.0, kaff=0.0), sp, cmd_limit)
    return float(np.max(np.abs(sp[:, 0] - xs))), ts, xs


def simulate(m: AxisModel, d: Design, setpoint: np.ndarray, cmd_limit: int = SYSTEM.pwm_full
             ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The design model in the loop with a set-point per control sample (rows: counts, counts/s,
    counts/s^2, the last two for the feed-forward): times (s), positions (counts), commands."""
    t_ctl = d.period_s
    sub = max(1, math.ceil(t_ctl / 2e-4))
    h = t_ctl / sub
    c = m.counts_per_motor_rad
    theta, w, integ = 0.0, 0.0, 0.0
    ts, xs, us = [], [], []
    for k, (target, v_sp, a_sp) in enumerate(setpoint):
        pos = math.floor(theta + 0.5)
        e = target - pos
        v = w * c
        u_lin = d.kp * e - d.kd * v + d.kvff * v_sp + d.kaff * a_sp
        cand = integ + d.ki * t_ctl * e
        u = u_lin + cand
        if abs(u) > cmd_limit and math.copysign(1, e) == math.copysign(1, u):
            u = u_lin + integ                   # held while saturated toward the error
        elif abs(e) <= d.izone_counts:
            u = u_lin + integ                   # the hunting guard
        else:
            integ = cand
        u += d.fc[0] if u > 0 else -d.fc[1] if u < 0 else 0
        u = max(-cmd_limit, min(cmd_limit, round(u)))
        duty = 0 if u == 0 else d.pw0 + abs(u) * (m.full - d.pw0) / m.full
        volts = math.copysign(duty / m.full * m.supply_v, u) if u else 0.0
        for _ in range(sub):
            if w == 0.0:
                brk_pos = m.breakaway_pct[0] / 100 * m.supply_v
                brk_neg = m.breakaway_pct[1] / 100 * m.supply_v
                if volts > brk_pos:
                    s = 1
                elif volts < -brk_neg:
                    s = -1
                else:
                    continue
            else:
                s = 1 if w > 0 else -1
            vf = m.friction_v[0] if s > 0 else -m.friction_v[1]
            w_new = w + h * (m.speed_gain * (volts - vf) - w) / m.tau
            if w != 0.0 and (w_new > 0) != (w > 0):      # crossed zero: stop, stick test next substep
                w_new = 0.0
            theta += h * (w + w_new) / 2 * c
            w = w_new if not (w == 0.0 and (w_new > 0) != (s > 0)) else 0.0
        ts.append((k + 1) * t_ctl)
        xs.append(math.floor(theta + 0.5))
        us.append(u)
    return np.array(ts), np.array(xs, dtype=float), np.array(us, dtype=float)
