# SPDX-License-Identifier: MIT
"""``torqueloop identify``: an axis's plant from its encoder alone, on a
connected board (real or simulated), with the open-loop drive (DRIVE).

Per direction, within the travel window the user gives:

1. **breakaway** (the paper's dead zone: raise the pulse until the system
   moves): bisection on the duty, each probe from rest; **stop duty** (lower
   it until the system stops): from motion, the duty stepped down until the
   encoder stops;
2. **a duty staircase** (three duties above the breakaway): the steady speed
   at each (a line against the applied volts: speed gain and friction
   voltage) and the rise after each step (the time constant);
3. **a coast-down** (the bridge off: BRAKE = 0 and disable): the speed's
   decay against the speed (friction and viscous drag over the inertia).

The fits are torqueloop/host/identfit.py's; their results are the plant
file's ``[identifiable.<axis>]`` keys with ``<key>_sigma`` beside each.  The
board's settings the procedure changes (PW0, PWMAX, PERIOD_US, BRAKE, LAW,
the telemetry rate) are restored afterwards, whatever happens; the axis is
disabled at the end, on any fault, and on Ctrl-C.

Every wait is in the board's time, read from its telemetry
(:class:`~torqueloop.host.session.BoardTime`): a simulated board slower or
faster than real time (``sim --rtl``, the in-process board of the tests) is
held as long as a real one.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from torqueloop.host import identfit as F
from torqueloop.host.client import Client, ProtocolError, describe_faults
from torqueloop.host.session import BoardTime
from torqueloop.spec import pwm
from torqueloop.spec.system import SYSTEM

FULL = pwm.full_scale()
#: encoder counts per motor radian (the speeds of the fits are rad/s at the motor)
COUNTS_PER_MOTOR_RAD = SYSTEM.counts_per_motor_rev / (2 * math.pi)


@dataclass(frozen=True)
class Plan:
    axis: int
    window_counts: int                  # travel allowed on either side of where the axis starts
    supply_v: float = 12.0
    resistance_ohm: float | None = None   # the loop's: winding (measured) + the bridge's two switches
    period_us: int = 1000               # control period while identifying (the telemetry's time base)
    telemetry_every: int = 5            # a frame every 5 periods: 200 Hz at 1 ms
    probe_s: float = 0.4                # breakaway probe: how long a duty is held from rest
    moved_counts: int = 3               # what counts as "moved" for a probe
    step_s: float = 1.2                 # longest hold of one staircase duty (shorter if the speed settles)
    staircase: tuple[float, ...] = (2.0, 3.5, 5.0)   # duties as multiples of the breakaway
    max_duty: float = 0.6               # never more than this (fraction)
    carrier_hz: float | None = SYSTEM.working_hz   # the carrier to identify at (None: the board's as set)


@dataclass
class Trace:
    t: np.ndarray          # s, board time
    pos: np.ndarray        # counts
    vel: np.ndarray        # counts/s (the firmware's edge-timestamp estimate)


@dataclass
class AxisResult:
    axis: int
    estimates: dict[str, float]
    directions: dict[str, F.Direction]
    traces: dict[str, list[tuple[float, Trace]]] = field(default_factory=dict)   # per direction: (duty, trace)
    seconds: float = 0.0


class IdentifyError(ProtocolError):
    """The procedure cannot go on (a fault, the travel window, no motion); one line."""


class _Axis:
    """The open-loop moves of one axis on a client."""

    def __init__(self, c: Client, plan: Plan) -> None:
        self.c, self.plan, self.a = c, plan, plan.axis
        self.start = c.status(self.a)["position"]
        self.board = BoardTime(c, every=plan.telemetry_every)      # the stream is the procedure's own

    def sleep(self, seconds: float) -> Trace:
        """Let ``seconds`` of the board's time pass (its telemetry's clock), feeding the link
        watchdog, and return the axis's telemetry over them."""
        rows = self.board.hold(seconds)
        ax = [r["axes"][self.a] for r in rows]
        t = np.unwrap(np.array([r["time_us"] for r in rows], dtype=float), period=2.0**32) * 1e-6   # u32 wraps
        trace = Trace(t, np.array([x["position"] for x in ax], dtype=float),
                      np.array([x["velocity_q8"] / 256 for x in ax], dtype=float))
        for x in ax:
            if x["faults"]:
                raise IdentifyError(f"axis {self.a} tripped: {describe_faults(x['faults'])}")
        return trace

    def drive(self, duty: float) -> None:
        steps = int(math.copysign(min(FULL, round(abs(duty) * FULL)), duty))
        if not self.c.status(self.a)["enabled"]:
            self.c.enable(1 << self.a, True)
        self.c.drive(self.a, steps)

    def release(self) -> None:
        """Disable: the bridge coasts (BRAKE is 0 while identifying)."""
        self.c.enable(1 << self.a, False)

    def position(self) -> int:
        return self.c.status(self.a)["position"]

    def room(self, sign: int) -> int:
        """Counts left before the window's edge in direction ``sign``."""
        return self.plan.window_counts - sign * (self.position() - self.start)

    def settle(self) -> None:
        """Wait (disabled) until the encoder stops."""
        last = self.position()
        for _ in range(40):
            self.sleep(0.05)
            now = self.position()
            if now == last:
                return
            last = now


def _breakaway(ax: _Axis, sign: int, say) -> float:
    plan = ax.plan

    def moves(duty: float) -> bool:
        ax.settle()
        if ax.room(sign) < 4 * plan.moved_counts:
            raise IdentifyError(f"axis {plan.axis}: the travel window is used up in the "
                                f"{'positive' if sign > 0 else 'negative'} direction")
        p0 = ax.position()
        ax.drive(sign * duty)
        held, moved = 0.0, False
        while held < plan.probe_s and not moved:
            tr = ax.sleep(0.02)
            held += float(tr.t[-1] - tr.t[0]) if tr.t.size else 0.02
            moved = abs(ax.position() - p0) >= plan.moved_counts
        ax.release()
        say(f"  {'+' if sign > 0 else '-'}{100 * duty:5.1f} %: {'moves' if moved else 'holds'}")
        return moved

    return F.bisect_threshold(moves, 0.0, plan.max_duty / 2, 1.0 / FULL)


def _stop_duty(ax: _Axis, sign: int, breakaway: float) -> float:
    """From motion at 1.5 x the breakaway, step the duty down until the encoder stops."""
    ax.settle()
    duty = min(ax.plan.max_duty, 1.5 * breakaway)
    ax.drive(sign * duty)
    ax.sleep(0.2)
    stopped_at = 0.0
    while duty > 0:
        duty -= 2.0 / FULL
        ax.drive(sign * duty)
        p0 = ax.position()
        ax.sleep(0.08)
        if abs(ax.position() - p0) < 1:
            stopped_at = duty
            break
    ax.release()
    return stopped_at


def _staircase(ax: _Axis, sign: int, breakaway: float) -> tuple[list[float], list[float], list[float], list[tuple[float, Trace]]]:
    plan = ax.plan
    volts, speeds, taus, traces = [], [], [], []
    duties = [min(plan.max_duty, m * breakaway) for m in plan.staircase]
    ax.settle()
    for d in duties:
        ax.drive(sign * d)
        tr = ax.sleep(plan.step_s)
        if ax.room(sign) < 0:
            raise IdentifyError(f"axis {plan.axis}: the staircase left the travel window; give a wider "
                                "window (--travel) or lower duties")
        if tr.t.size < 8:
            raise IdentifyError(f"axis {plan.axis}: {tr.t.size} telemetry frames in {plan.step_s} s: "
                                "the link cannot carry the telemetry rate (raise --telemetry-every)")
        w = np.abs(tr.vel) / COUNTS_PER_MOTOR_RAD
        e = F.fit_exponential(tr.t, w, 1e-3, 10.0)      # shift-invariant: the origin is free
        volts.append(d * plan.supply_v)
        speeds.append(e.final)
        taus.append(e.tau)
        traces.append((sign * d, tr))
    return volts, speeds, taus, traces


def _coast(ax: _Axis, sign: int, w_top: float) -> F.Line | None:
    ax.release()
    tr = ax.sleep(0.8)
    w = np.abs(tr.vel) / COUNTS_PER_MOTOR_RAD
    sel = (w > 0.15 * w_top) & (w < 0.9 * w_top)
    if sel.sum() < 6:
        return None
    t, w = tr.t[sel], w[sel]
    acc = np.diff(w) / np.diff(t)
    return F.fit_line((w[1:] + w[:-1]) / 2, acc)


#: parameters the procedure changes, restored afterwards (axis scope; PERIOD_US is global)
AXIS_SETTINGS = ("PW0", "PWMAX", "BRAKE", "LAW", "FDIV", "ENC_CMD0")


def identify_axis(c: Client, plan: Plan, say: Callable[[str], None] = lambda m: None) -> AxisResult:
    """The whole procedure on one axis (module docstring)."""
    a = plan.axis
    saved = {k: c.get_param(k, a) for k in AXIS_SETTINGS}
    period = c.get_param("PERIOD_US", 0)
    t0 = c.clock()
    ax = None
    try:
        c.enable(1 << a, False)
        c.set_param("LAW", 0, a)           # no position law: the drive alone moves it
        c.set_param("PW0", 0, a)           # command = duty ticks
        c.set_param("PWMAX", FULL, a)
        c.set_param("BRAKE", 0, a)         # disable coasts (the coast-down)
        c.set_param("PERIOD_US", plan.period_us, 0)
        if plan.carrier_hz is not None:
            c.set_param("FDIV", pwm.divider_for(plan.carrier_hz), a)
        c.set_telemetry(plan.telemetry_every)
        ax = _Axis(c, plan)
        dirs, traces = {}, {}
        for name, sign in (("pos", +1), ("neg", -1)):
            # The encoder check expects motion above ENC_CMD0; the breakaway search holds duties
            # inside the dead zone it measures, where a healthy, stuck rotor would trip it. It is
            # raised to the search's ceiling for the search (the stall check, the travel window and
            # the soft limits still guard) and set just above the measured breakaway for the rest.
            ax.release()
            c.set_param("ENC_CMD0", round(plan.max_duty / 2 * FULL), a)
            say(f"axis {a} {name}: breakaway")
            brk = _breakaway(ax, sign, say)
            ax.release()
            c.set_param("ENC_CMD0", min(FULL, round(1.5 * brk * FULL)), a)
            say(f"axis {a} {name}: breakaway {100 * brk:.2f} %; stop duty")
            stop = _stop_duty(ax, sign, brk)
            say(f"axis {a} {name}: stops at {100 * stop:.2f} %; staircase")
            volts, speeds, taus, tr = _staircase(ax, sign, brk)
            coast = _coast(ax, sign, speeds[-1])
            dirs[name] = F.Direction(F.fit_line(volts, speeds), float(np.mean(taus)),
                                     float(np.std(taus) / math.sqrt(len(taus))), coast, 100 * brk, 100 * stop)
            traces[name] = tr
            say(f"axis {a} {name}: {speeds[-1]:.0f} rad/s at {volts[-1]:.2f} V, tau {np.mean(taus) * 1e3:.0f} ms")
        est = F.estimates(dirs["pos"], dirs["neg"], plan.resistance_ohm)
        return AxisResult(a, est, dirs, traces, c.clock() - t0)
    finally:
        try:
            c.enable(1 << a, False)
            c.set_telemetry(0)
            for k, v in saved.items():
                c.set_param(k, v, a)
            c.set_param("PERIOD_US", period, 0)
        except ProtocolError:
            pass
