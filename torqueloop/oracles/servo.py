# SPDX-License-Identifier: MIT
"""Reference model of one servo axis (docs/firmware.md, "Control"), in Python
integers: the oracle for firmware/servo/control.c (host tests drive both with
the same random inputs) and for the on-SoC firmware bench.

Formats: gains q16 (PWM steps per count, per count/s, per count*s), set-point
q16 counts, velocity q8 counts/s, integrator q32 PWM steps; the PWM command
is round(u) saturated to +-cmd_limit (eq. 19/25).  The law is eq. (20)-(22)
with the derivative taken from the measured velocity:
    u = Kp e - Kd v + I,    I_k = I_{k-1} + Ki T_s e_k   (held while saturated
                                                         toward the error)
plus the friction compensation and the dither (``friction_terms``, ``dither_q16``).
"""

from __future__ import annotations

from dataclasses import dataclass
from torqueloop.spec.system import SYSTEM



def clamp(v: int, limit: int) -> int:
    return max(-limit, min(limit, v))


def round_q16(u_q16: int) -> int:
    """Nearest integer of a q16 value, halves up (arithmetic shift, like the C)."""
    return (u_q16 + 32768) >> 16


def count_diff(a: int, b: int) -> int:
    """Counts between two decoder readings, modulo 2^32 like the 32-bit counter
    (control.c's count_diff: the counter wraps, the difference does not jump)."""
    return ((a - b + (1 << 31)) & 0xFFFF_FFFF) - (1 << 31)


#: control.c's limits: profile speed and acceleration per sample (q16 counts),
#: counts between two velocity samples
VMAX_Q16_MAX = 0x4000_0000
AMAX_Q16_MAX = 0x2000_0000
DCOUNT_MAX = 0x0FFF_FFFF


def stop_sum(v: int, a: int) -> int:
    """S(v): the distance braking by ``a`` per sample covers after a sample at speed
    ``v`` (>= 0) until the speed would reach zero: (v - a) + (v - 2a) + ... over the
    positive terms."""
    m = max(0, (v - 1) // a)                 # the positive terms v - j a, j = 1 .. m
    return m * v - a * m * (m + 1) // 2


#: the profile's regimes (control.h TL_PROF_*): speeding up or cruising, braking onto the
#: target, braking by a past a target it could not stop for
ACCEL, BRAKE, OVERRUN = 0, 1, 2


def edge_speed_q8(counts: int, dt: int, clk_hz: int) -> int:
    """``counts`` (>= 0) over ``dt`` (> 0) clock cycles in q8 counts/s, saturated to
    2^31 - 1: N = counts clk 2^8 brought below 2^32 by the smallest right shift k,
    then (floor(N / 2^k) // dt) << k - one 32-bit divide in control_step.h; below the
    exact N // dt by less than 2^(k+1)."""
    n = min(counts, DCOUNT_MAX) * clk_hz * 256
    k = max(0, n.bit_length() - 32)
    return min(((n >> k) // dt) << k, (1 << 31) - 1)


def _tdiv(a: int, b: int) -> int:
    """C integer division (truncates toward zero)."""
    q = abs(a) // abs(b)
    return q if (a >= 0) == (b >= 0) else -q


def in_izone(p: "AxisParams", e_q16: int) -> bool:
    """The hunting guard: the integral is frozen while |e| <= IZONE_Q16 (0: off)."""
    return p.izone_q16 != 0 and abs(e_q16) <= p.izone_q16


def friction_terms(p: "AxisParams", u_q16: int, prof_v_q16: int, euler_k: int, prof_a_q16: int) -> int:
    """The law's output (q16 PWM steps, before rounding) with the friction
    compensation of control_step.h: the velocity feed-forward Kvff v_sp (v_sp
    the profile's speed in q8 counts/s, saturated to 31 bits), the acceleration
    feed-forward Kaff a_sp (a_sp the profile speed's change over the sample in
    q8 counts/s^2: the change in q8 counts/s, then per second, each saturated to
    31 bits), then FC_POS added to a positive output, FC_NEG to the size of a
    negative one (the sign of P + D + I + feed-forward, before rounding)."""
    lim = (1 << 31) - 1
    if p.kvff_q16 and prof_v_q16:
        v_q8 = clamp((prof_v_q16 * euler_k) >> 16, lim)
        u_q16 += (p.kvff_q16 * v_q8) >> 8
    if p.kaff_q16 and prof_a_q16:
        dv_q8 = clamp((prof_a_q16 * euler_k) >> 16, lim)
        a_q8 = clamp((dv_q8 * euler_k) >> 8, lim)
        u_q16 += (p.kaff_q16 * a_q8) >> 8
    if u_q16 > 0:
        u_q16 += p.fc_pos << 16
    elif u_q16 < 0:
        u_q16 -= p.fc_neg << 16
    return u_q16


def dither_on(p: "AxisParams", e_q16: int) -> bool:
    """The dither acts while the error (after the dead band) is nonzero and outside
    the hunting guard's zone: an axis at rest on its target does not buzz."""
    return p.dither_amp != 0 and e_q16 != 0 and not in_izone(p, e_q16)


def dither_q16(p: "AxisParams", n: int) -> tuple[int, int]:
    """The square wave of control_step.h, q16 PWM steps, at sample ``n`` of its period
    (+DITHER_AMP while n < DITHER_HALF, -DITHER_AMP after), and the next ``n``."""
    d = p.dither_amp << 16 if n < p.dither_half else -(p.dither_amp << 16)
    n += 1
    return d, (0 if n >= 2 * p.dither_half else n)


@dataclass
class AxisParams:
    law: int = 1
    kp_q16: int = 0
    kd_q16: int = 0
    ki_q16: int = 0
    deadband_q16: int = 0x8000
    cmd_limit: int = SYSTEM.pwm_full
    vel_mode: int = 1
    vmax_cps: int = 8400
    amax_cps2: int = 16800
    # friction compensation (control_step.h friction_terms, the integral's hunting guard); 0: none
    fc_pos: int = 0
    fc_neg: int = 0
    izone_q16: int = 0
    kvff_q16: int = 0
    # square-wave dither (control_step.h friction_terms): amplitude in PWM steps (0: off), half-period in samples
    dither_amp: int = 0
    dither_half: int = 1
    # acceleration feed-forward (control_step.h friction_terms): q16 PWM steps per count/s^2 of the profile's speed change
    kaff_q16: int = 0


@dataclass
class Axis:
    p: AxisParams
    period_us: int
    clk_hz: int = SYSTEM.clk_hz
    sp_q16: int = 0
    target_q16: int = 0
    prof_v_q16: int = 0
    prof_a_q16: int = 0          # the profile speed's change over the last sample (0 at rest and on landing)
    moving: bool = False
    # the profile's plan (_plan, _profile): regime, direction toward the target (+1 / -1), the braking
    # surplus E = d - S(v) (ACCEL; d while moving away; d - S(v) < 0 in OVERRUN), the braking level and
    # the two speeds still to insert into the braking (BRAKE)
    prof_st: int = ACCEL
    prof_s: int = 1
    prof_e: int = 0
    prof_b: int = 0
    prof_p1: int = 0
    prof_p2: int = 0
    integ_q32: int = 0
    saturated: bool = False
    sat_sign: int = 0
    vel_q8: int = 0
    pos_prev: int = 0
    pos_ref: int = 0
    moved_last: bool = False
    t_ref: int = 0
    cmd: int = 0
    dither_n: int = 0

    def __post_init__(self) -> None:
        self.derive()

    def derive(self) -> None:
        p, T = self.p, self.period_us
        self.ki_dt_q32 = _tdiv(p.ki_q16 * T * 1024, 15625)
        # |e| up to 2^(61 - bitlen(ki_dt)) keeps ki_dt * e below 2^61 (control.c); beyond
        # it the integrator saturates either way
        kb = self.ki_dt_q32.bit_length()
        self.e_max = 0x7FFF_FFFF if kb <= 30 else 1 << (61 - kb)
        self.vmax_q16 = min(VMAX_Q16_MAX, max(1, _tdiv(p.vmax_cps * T * 1024, 15625)))
        self.amax_q16 = min(AMAX_Q16_MAX, max(1, _tdiv(p.amax_cps2 * T * T * 16, 244140625)))
        # the Euler difference's scale, rounded once: q8 counts/s per count per sample
        self.euler_k = (256_000_000 + T // 2) // T
        self.s_vmax = stop_sum(self.vmax_q16, self.amax_q16)
        self._plan()    # a new VMAX or AMAX mid-move: planned again from where the profile is

    def reset(self, pos: int, now: int) -> None:
        self.sp_q16 = self.target_q16 = pos << 16
        self.prof_v_q16, self.prof_a_q16, self.moving, self.integ_q32 = 0, 0, False, 0
        self.saturated, self.sat_sign, self.vel_q8 = False, 0, 0
        self.pos_prev = self.pos_ref = pos
        self.t_ref = now
        self.moved_last = False
        self.cmd = 0
        self.dither_n = 0

    def move(self, target: int, trapezoid: bool) -> None:
        self.target_q16 = target << 16
        if trapezoid:
            self.moving = True
            self._plan()
        else:
            self.sp_q16, self.prof_v_q16, self.prof_a_q16, self.moving = self.target_q16, 0, 0, False

    def _plan(self) -> None:
        """The profile's regime from where it is (a new target, VMAX or AMAX): toward the
        target, moving away from it (speed up toward it, ACCEL with E = d), able to stop
        before it (ACCEL, E = d - S(v) >= 0) or not (OVERRUN: brake by a past it, then come
        back)."""
        if not self.moving:
            return
        d = self.target_q16 - self.sp_q16
        self.prof_s = 1 if d >= 0 else -1
        v = self.prof_v_q16 * self.prof_s
        self.prof_e = abs(d) - (stop_sum(v, self.amax_q16) if v > 0 else 0)
        self.prof_st = ACCEL if self.prof_e >= 0 else OVERRUN
        if v > self.vmax_q16 and self.prof_st == ACCEL:   # above a lowered vmax: E at vmax, where it drops to
            self.prof_e = abs(d) - self.s_vmax

    def _land(self) -> None:
        """The last sample: on the target, which the speeds sum to."""
        self.sp_q16, self.prof_v_q16, self.prof_a_q16, self.moving = self.target_q16, 0, 0, False

    def _profile(self) -> None:
        """One sample of the trapezoid (docs/firmware.md, "Fourth pass"), in the frame
        toward the target (speed v, distance d): speed up by a to at most vmax while the
        surplus E = d - S(v) stays >= 0 (braking by a from the new speed still stops
        short of the target); when it would not, brake from the last speed b by a per
        sample with the rest R = d - S(b) (< 2 b + a) added as at most two more samples,
        merged in descending order (so no step changes the speed by more than a), and land
        exactly on the target with the last one."""
        if not self.moving:
            return
        a, vmax, s = self.amax_q16, self.vmax_q16, self.prof_s
        v = self.prof_v_q16 * s
        w = 0
        if self.prof_st == OVERRUN:
            w = v - a                      # v > a; E = d - S(v) is the same after braking by a
            self._out(w * s)
            if w <= a:                     # the last speed past the target: turn toward it
                self.prof_s, self.prof_e, self.prof_st = -s, -self.prof_e, ACCEL   # S(w) = 0: E is d
            return
        if self.prof_st == ACCEL:
            u = min(v + a, vmax)
            # what the sample takes from E: u + S(u) - S(v), which is u + v speeding up by a (S(v + a)
            # = S(v) + v), vmax cruising; reaching vmax, u + v again (S(vmax) <= S(v + a): E falls
            # below d - S(v) by at most v, so a braking from vmax takes its rest from d, below)
            e = self.prof_e - (u if v >= vmax else u + max(v, 0))
            if u <= 0 or e >= 0:
                self.prof_e, w = e, u
            else:                          # brake: from b = v, or from vmax
                b = min(max(v, 0), vmax)
                r = (self.target_q16 - self.sp_q16) * s - self.s_vmax if b == vmax else self.prof_e
                self.prof_p2 = min(b, r // 2)
                self.prof_p1, self.prof_b, self.prof_st = r - self.prof_p2, b, BRAKE
        if self.prof_st == BRAKE:
            nb = self.prof_b - a
            if self.prof_p1 > 0 and self.prof_p1 >= nb:
                w, self.prof_p1, self.prof_p2 = self.prof_p1, self.prof_p2, 0
            elif nb > 0:
                w = self.prof_b = nb
            if self.prof_p1 == 0 and self.prof_b - a <= 0:
                self._land()               # the last sample: on the target (the speeds sum to d)
                return
        self._out(w * s)

    def _out(self, v: int) -> None:
        """The sample's speed ``v`` (signed) into the set-point."""
        self.prof_a_q16 = v - self.prof_v_q16
        self.prof_v_q16 = v
        self.sp_q16 += v

    def _velocity(self, pos: int, edge_time: int, now: int, interval: int) -> None:
        clamp32 = (1 << 31) - 1
        if self.p.vel_mode == 0:
            euler = count_diff(pos, self.pos_prev) * self.euler_k
            self.vel_q8 = clamp(_tdiv(euler + self.vel_q8, 2), clamp32)
        elif pos != self.pos_ref:
            # edge-to-edge average while moving; one count over the last edge interval
            # for the first counts after a silent sample
            d, dt = count_diff(pos, self.pos_ref), (edge_time - self.t_ref) & 0xFFFFFFFF
            if not self.moved_last:
                d, dt = (1 if d > 0 else -1), interval
            v = edge_speed_q8(abs(d), dt or 1, self.clk_hz)
            self.vel_q8 = -v if d < 0 else v
            self.pos_ref, self.t_ref, self.moved_last = pos, edge_time, True
        else:
            self.moved_last = False
            dt = (now - self.t_ref) & 0xFFFFFFFF
            if dt > 0x7FFFFFFF:
                self.t_ref = (now - 0x7FFFFFFF) & 0xFFFFFFFF
            bound = edge_speed_q8(1, dt, self.clk_hz) if dt else clamp32
            if abs(self.vel_q8) > bound:
                self.vel_q8 = bound if self.vel_q8 > 0 else -bound
        self.pos_prev = pos

    def step(self, pos: int, edge_time: int, now: int, run: bool = True, interval: int = 0) -> int:
        p = self.p
        self._velocity(pos, edge_time, now, interval)
        self._profile()
        e = self.sp_q16 - (pos << 16)
        if not run or p.law == 0:
            self.integ_q32, self.cmd, self.dither_n = 0, 0, 0
            return 0
        if abs(e) <= p.deadband_q16:
            e = 0
        e = clamp(e, (1 << 31) - 1)
        lim = p.cmd_limit
        u = (p.kp_q16 * e) >> 16
        if p.law >= 2:
            u -= (p.kd_q16 * self.vel_q8) >> 8
        if p.law == 3:
            sign = (e > 0) - (e < 0)
            if not (self.saturated and sign == self.sat_sign) and not in_izone(p, e):
                inc = (self.ki_dt_q32 * clamp(e, self.e_max)) >> 16
                self.integ_q32 = clamp(self.integ_q32 + inc, lim << 32)
            u += self.integ_q32 >> 16
        else:
            self.integ_q32 = 0
        u = friction_terms(p, u, self.prof_v_q16, self.euler_k, self.prof_a_q16)
        if dither_on(p, e):
            d, self.dither_n = dither_q16(p, self.dither_n)
            u += d
        out = round_q16(u)
        self.saturated = abs(out) > lim
        self.sat_sign = 1 if out > lim else (-1 if out < -lim else 0)
        self.cmd = clamp(out, lim)
        return self.cmd


@dataclass
class EncCheck:
    """The encoder plausibility check of firmware/servo/enc_check.h, bit for
    bit in Python integers (docs/safety.md): per period, the command applied
    during it, the position and the measured speed (q8 counts/s) at its end;
    ``step`` returns True when RUNAWAY trips."""

    cmd0: int
    cps: int
    tau_ms: int
    slack: int
    period_us: int
    dir: int = 0
    ref: int = 0
    vlo_q8: int = 0
    behind_q24: int = 0

    def __post_init__(self) -> None:
        self.k_q8 = self.cps * 256 // (2 * SYSTEM.pwm_full)
        self.alpha_q16 = min(65536, (self.period_us << 16) // (self.tau_ms * 1000))
        self.dt_q16 = (self.period_us << 16) // 1_000_000

    def step(self, cmd: int, pos: int, vel_q8: int) -> bool:
        d = 1 if cmd > self.cmd0 else (-1 if cmd < -self.cmd0 else 0)
        if d == 0 or d != self.dir:
            self.dir, self.ref, self.behind_q24, self.vlo_q8 = d, pos, 0, d * vel_q8
            return False
        v_ss = (abs(cmd) - self.cmd0) * self.k_q8
        if v_ss <= self.vlo_q8:
            self.vlo_q8 = v_ss
        else:
            self.vlo_q8 += ((v_ss - self.vlo_q8) * self.alpha_q16) >> 16
        if self.vlo_q8 <= 0:
            self.ref, self.behind_q24 = pos, 0
            return False
        self.behind_q24 += self.vlo_q8 * self.dt_q16
        moved = count_diff(pos, self.ref) * d
        self.ref = pos
        behind = self.behind_q24 - (moved << 24)
        self.behind_q24 = max(behind, 0)
        return behind > (self.slack << 24)
