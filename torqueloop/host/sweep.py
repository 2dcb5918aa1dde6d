# SPDX-License-Identifier: MIT
"""The board as the characterisation's PWM source (``torqueloop
characterize sweep``).  Encoder-only (docs/characterization.md, "Without a
force gauge"): at each PWM carrier and in each direction, the dead zone as the
paper defines it - raise the pulse until the system moves (the breakaway
duty), then lower it until it stops (the stop duty) - measured with the
open-loop drive (DRIVE) and the encoder alone.

Each step holds the duty for ``hold_s`` of the board's time (its telemetry's
clock, :class:`~torqueloop.host.session.BoardTime`: a simulated board slower
than real time is held as long) and calls the axis moving when the
encoder advanced at least ``move_counts`` in the duty's direction during the
second half of the hold (the first half lets it speed up or coast down to
the new duty).  The duty ramps up from ``start`` by ``step`` until it moves (or
``stop_at``), then down by ``step`` until it no longer does.  The axis is
enabled once per ramp and disabled after it, whatever happens (a fault, a
refusal, Ctrl-C).

Safety is the firmware's, unchanged: a duty of STALL_CMD or more that does
not move the axis within STALL_MS trips RUNAWAY and ends the ramp; a motor
whose breakaway lies above STALL_CMD needs that check raised first (with
every axis disabled), which this tool never does by itself.

With a force gauge (:func:`hold_and_read`; docs/characterization.md, "The
board as the PWM source, with a force gauge"): the board holds each setting of
the method's sweeps - the stall reading fully on, the 50 % frequency sweep,
the duty sweeps - and the lab's reading of the gauge and the ammeter is taken
while it holds (torqueloop/characterize/board.py asks for it or looks it up,
and runs the method).  A stalled motor at STALL_CMD or more trips RUNAWAY
STALL_MS after the setting starts: the reading must come before that.
"""

from __future__ import annotations

from contextlib import contextmanager
from dataclasses import asdict, dataclass
from typing import Callable

from torqueloop.host.client import Client, ProtocolError, describe_faults
from torqueloop.host.drive import check_ready, steps_for
from torqueloop.host.session import BoardTime, board_s
from torqueloop.spec import pwm


@dataclass
class Ramp:
    carrier_hz: float
    direction: int                 # +1 / -1
    breakaway_percent: float | None  # first duty that moved it (None: none up to stop_at)
    stop_percent: float | None     # first duty on the way down that no longer did
    points: list[tuple[float, int]]  # (duty %, counts moved during its hold), in order
    fault: str = ""


def _moved(c: Client, bt: BoardTime, axis: int, steps: int, hold_s: float, faults0: int) -> tuple[int, int]:
    """Drive at ``steps`` for ``hold_s`` of the board's time (its telemetry's clock); the counts
    moved in the second half of the hold (the first lets the speed settle at the new duty), and
    the faults latched since ``faults0``.  A new fault ends the hold."""
    c.drive(axis, steps)
    recs = bt.hold(hold_s, until=lambda r: bool(r["axes"][axis]["faults"] & ~faults0))
    t0 = recs[0]["time_us"]
    mid = next((r for r in recs if board_s(t0, r["time_us"]) >= hold_s / 2), recs[-1])
    last = recs[-1]["axes"][axis]
    return last["position"] - mid["axes"][axis]["position"], last["faults"] & ~faults0


def ramp(c: Client, axis: int, direction: int, carrier_hz: float, *, start: float = 1.0, step: float = 0.5,
         stop_at: float = 30.0, hold_s: float = 0.3, move_counts: int = 3) -> Ramp:
    """One up-and-down ramp in ``direction`` at the carrier already set (FDIV)."""
    r = Ramp(carrier_hz, direction, None, None, [])
    faults0 = check_ready(c, axis, steps_for(direction * stop_at))["faults"]
    c.enable(1 << axis, True)
    try:
        with BoardTime(c) as bt:
            return _ramp(c, bt, r, axis, direction, faults0, start, step, stop_at, hold_s, move_counts)
    finally:
        c.enable(1 << axis, False)


def _ramp(c: Client, bt: BoardTime, r: Ramp, axis: int, direction: int, faults0: int, start: float, step: float,
          stop_at: float, hold_s: float, move_counts: int) -> Ramp:
    """The duty up from ``start`` until the axis moves, then down until it stops (``ramp``)."""

    def point(duty: float) -> int | None:
        """The counts moved at ``duty``, or None when a fault ended the ramp."""
        moved, fault = _moved(c, bt, axis, steps_for(direction * duty), hold_s, faults0)
        r.points.append((round(duty, 3), moved))
        if fault:
            r.fault = describe_faults(fault)
            return None
        return moved * direction

    duty = start
    while duty <= stop_at + 1e-9:
        moved = point(duty)
        if moved is None:
            return r
        if moved >= move_counts:
            r.breakaway_percent = round(duty, 3)
            break
        duty += step
    if r.breakaway_percent is None:
        return r
    while duty > 0:
        duty = max(0.0, duty - step)   # at 0 the bridge brakes: it stops there at the latest
        moved = point(duty)
        if moved is None:
            return r
        if moved < move_counts:
            r.stop_percent = round(duty, 3)
            break
    return r


@contextmanager
def _carrier_control(c: Client, axis: int, clk_hz: int):
    """Yields ``set_carrier(hz) -> the carrier the board makes`` (eq. 4's
    divider, refused above PWM_MAX_HZ); the axis's FDIV is restored at the end,
    whatever happens."""
    fdiv0 = c.get_param("FDIV", axis)
    pwm_max = c.get_param("PWM_MAX_HZ")

    def set_carrier(f: float) -> float:
        div = pwm.divider_for(f, clk_hz)
        actual = round(pwm.carrier_hz(div, clk_hz), 3)
        if actual > pwm_max:
            raise ProtocolError(f"a {f:g} Hz carrier is above PWM_MAX_HZ = {pwm_max} Hz")
        if c.get_param("FDIV", axis) != div:
            c.set_param("FDIV", div, axis)
        return actual

    try:
        yield set_carrier
    finally:
        c.set_param("FDIV", fdiv0, axis)


def _kept(out: list, point, log) -> bool:
    """Add a point to the list and the log; True when its fault ends the session."""
    out.append(point)
    if log:
        log(point)
    return bool(point.fault)


def sweep(c: Client, axis: int, carriers_hz: list[float], clk_hz: int, log=None, **kw) -> list[Ramp]:
    """A ramp per carrier and direction; the axis's FDIV is restored afterwards."""
    out: list[Ramp] = []
    with _carrier_control(c, axis, clk_hz) as set_carrier:
        for f in carriers_hz:
            actual = set_carrier(f)
            for direction in (1, -1):
                if _kept(out, ramp(c, axis, direction, actual, **kw), log):
                    return out
    return out


def as_rows(ramps: list[Ramp]) -> list[dict]:
    return [{k: v for k, v in asdict(r).items()} for r in ramps]


# ---------------------------------------------------------------- with a force gauge

@dataclass
class GaugePoint:
    """One setting of the method's sweeps held by the board, with what the lab read at it."""
    sweep: str                     # "stall" (step 2: fully on), "frequency" (steps 3-4) or "duty" (step 6)
    carrier_hz: float              # the carrier the board made (eq. 4: the divider's nearest)
    duty_pct: float                # the command, percent of the full one
    force_n: float | None          # the gauge and the ammeter, as read
    current_a: float | None
    moved_counts: int              # encoder counts during the hold: about 0 on a stalled motor
    fault: str = ""


#: (sweep, carrier Hz, duty %, keepalive) -> (force N, current A), read while the board holds the
#: setting; ``keepalive()`` feeds the link watchdog and must be called at least every 0.1 s meanwhile
Reader = Callable[[str, float, float, Callable[[], None]], "tuple[float, float]"]


def hold_and_read(c: Client, axis: int, clk_hz: int, settings: list[tuple[str, float, float]], read: Reader,
                  settle_s: float = 0.5, log=None) -> list[GaugePoint]:
    """Hold each (sweep, carrier Hz, duty %) on ``axis`` - FDIV set while the axis is
    disabled, then enabled and driven open-loop at the duty - for ``settle_s``, then
    ask ``read`` for the gauge and the ammeter while it keeps holding.  The axis is
    disabled after each setting and its FDIV restored at the end, whatever happens;
    a fault ends the list (its point says which)."""
    out: list[GaugePoint] = []
    check_ready(c, axis, max((steps_for(d) for _, _, d in settings), key=abs, default=0))
    with _carrier_control(c, axis, clk_hz) as set_carrier:
        for kind, f, duty in settings:
            actual = set_carrier(f)
            st = check_ready(c, axis, steps_for(duty))
            c.enable(1 << axis, True)
            try:
                c.drive(axis, steps_for(duty))
                with BoardTime(c) as bt:
                    bt.hold(settle_s)
                now = c.status(axis)
                fault = now["faults"] & ~st["faults"]
                p = GaugePoint(kind, actual, duty, None, None, now["position"] - st["position"],
                               describe_faults(fault) if fault else "")
                if not fault:
                    p.force_n, p.current_a = read(kind, actual, duty, c.heartbeat)
                    after = c.status(axis)
                    fault = after["faults"] & ~st["faults"]
                    p.moved_counts = after["position"] - st["position"]
                    p.fault = describe_faults(fault) if fault else ""
            finally:
                c.enable(1 << axis, False)
            if _kept(out, p, log):
                return out
    return out
