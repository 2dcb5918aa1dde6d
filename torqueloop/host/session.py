# SPDX-License-Identifier: MIT
"""What the host tool does with the board beyond one command: a move that
enables its axis for the move, waiting for a move or a homing to end, and a
telemetry capture, the waits and the capture feeding the link watchdog.  The host asks the board: a refusal comes back with the rule
that refused it (``CommandRejected.why``, protocol.toml [[refusal]]), so the
host keeps no copy of the firmware's rules, with one exception: MOVE's rule
(:func:`move_refusal`) is applied before an axis is enabled for a move, so
that a move the board would refuse never enables its axis.
tests/test_host_session.py shows on the simulated board that the host and
the firmware refuse exactly the same moves."""

from __future__ import annotations

import math
import time
from dataclasses import dataclass
from typing import Callable

from torqueloop.spec import protocol as P

from .client import Client, CommandRejected, ProtocolError

HOMING, HOMED = (next(k for k, v in P.HOME_STATE.items() if v == s) for s in ("homing", "homed"))
#: at rest: slower than this (counts/s x 256)
SETTLED_Q8 = 256 * 50
#: how often a capture or a wait sends a HEARTBEAT (the firmware's link watchdog: LINK_TIMEOUT_MS >= 10 ms, default 0.5 s)
KEEPALIVE_S = 0.15


@dataclass(frozen=True)
class MoveLimits:
    """The parameters MOVE's rule reads, counts."""
    soft_min: int
    soft_max: int
    follow_limit: int


def move_refusal(st: dict[str, int], lim: MoveLimits, target: int, trapezoid: bool, unhomed: bool,
                 enabled: bool | None = None) -> tuple[str, str] | None:
    """(status, rule) with which the board refuses MOVE to ``target`` from the
    state ``st`` (a STATUS reply), None if it accepts it; the checks and their
    order of ``cmd_move`` (firmware/servo/commands.c).  ``enabled``: judge as
    if the axis were enabled (or not), for a move that enables its axis first."""
    if not (st["enabled"] if enabled is None else enabled):
        return "STATE", "DISABLED"
    if st["home"] == HOMING:
        return "STATE", "HOMING"
    if st["home"] != HOMED and not unhomed:
        return "NOT_HOMED", "NOT_HOMED"
    if not lim.soft_min <= target <= lim.soft_max:
        return "RANGE", "OUTSIDE_SOFT"
    pos = st["position"]
    soft = P.LIMIT_BITS["neg"] if pos < lim.soft_min else (P.LIMIT_BITS["pos"] if pos > lim.soft_max else 0)
    blocked = st["limits"] | soft | (P.LIMIT_BITS["neg"] if st["faults"] & P.FAULT["LIMIT_NEG"] else 0) \
        | (P.LIMIT_BITS["pos"] if st["faults"] & P.FAULT["LIMIT_POS"] else 0)
    if (blocked & P.LIMIT_BITS["neg"] and target < pos) or (blocked & P.LIMIT_BITS["pos"] and target > pos):
        return "RANGE", "LIMIT"
    if not trapezoid and abs(target - pos) > lim.follow_limit:
        return "RANGE", "FOLLOW"
    return None


class Session:
    """The host tool's work on one board, over a :class:`Client`."""

    def __init__(self, client: Client) -> None:
        self.client = client

    def move_limits(self, axis: int) -> MoveLimits:
        c = self.client
        return MoveLimits(c.get_param("SOFT_MIN", axis), c.get_param("SOFT_MAX", axis),
                          c.get_param("FOLLOW_LIMIT", axis))

    def check_move(self, axis: int, target: int, trapezoid: bool, unhomed: bool, st: dict[str, int],
                   enabling: bool) -> None:
        """Raise the board's own refusal of this move, before anything is sent
        (``enabling``: the axis is to be enabled for it)."""
        r = move_refusal(st, self.move_limits(axis), target, trapezoid, unhomed, True if enabling else None)
        if r is not None:
            raise CommandRejected("MOVE", P.STATUS[r[0]], why=P.REFUSAL[r[1]],
                                  detail=f"(axis {axis}, target {target}, position {st['position']} counts; "
                                         "checked before sending)")

    def move(self, axis: int, target: int, trapezoid: bool = False, unhomed: bool = False,
             enable: bool = False, st: dict[str, int] | None = None) -> bool:
        """MOVE, enabling the axis first if asked and needed (and disabling it
        again if the move is refused after all).  Returns whether it enabled it."""
        c = self.client
        st = c.status(axis) if st is None else st
        enabling = enable and not st["enabled"]
        self.check_move(axis, target, trapezoid, unhomed, st, enabling)
        if enabling:
            c.enable(1 << axis, True)
        try:
            c.move(axis, target, trapezoid, unhomed)
        except ProtocolError:
            if enabling:
                c.enable(1 << axis, False)
            raise
        return enabling

    def capture(self, duration: float, every: int = 1, on_record: Callable[[dict], None] | None = None,
                trigger: tuple[float, Callable[[], None]] | None = None,
                on_progress: Callable[[float], None] | None = None, silence_s: float = 5.0) -> list[dict]:
        """Stream telemetry for ``duration`` seconds of *board* time (the records'
        time_us, so a co-simulation slower than real time is captured just as
        long), feeding the link watchdog; ``trigger`` = (t, fn) calls fn once the
        capture spans t seconds; ``on_progress(span)`` after each read.  No
        record for ``silence_s`` seconds is an error.  Returns the records."""
        with BoardTime(self.client, every=every, silence_s=silence_s) as bt:
            records = bt.hold(duration, on_record, trigger=trigger, on_progress=on_progress)
        return records + bt.tail


def board_s(t0_us: int, t1_us: int) -> float:
    """Seconds of the board's time from ``t0_us`` to ``t1_us`` (telemetry ``time_us``, a u32
    that wraps every 71.6 minutes)."""
    return ((t1_us - t0_us) % (1 << 32)) / 1e6


def telemetry_every(c: Client, record_s: float) -> int:
    """Control periods per telemetry record for about one record every
    ``record_s`` seconds of board time (PERIOD_US, the board's own)."""
    return max(1, min(0xFFFF, math.ceil(record_s * 1e6 / c.get_param("PERIOD_US"))))


class BoardTime:
    """Waits counted in the board's time, not the host's: the telemetry
    stream is on while the ``with`` block runs, and :meth:`hold` lasts until
    its records' ``time_us`` span the time asked.  A simulated board slower
    than real time (``torqueloop sim --speed``, ``sim --rtl``, a loaded
    machine) is held just as long as a real one, so what is read at the end
    of a hold is what the board did in that time.  Every wait feeds the link
    watchdog; no record for ``silence_s`` seconds of host time is an error.
    Records span at most one record interval (``every`` control periods)
    more than asked."""

    def __init__(self, c: Client, every: int | None = None, record_s: float = 0.02,
                 silence_s: float = 5.0) -> None:
        self.client = c
        self.every = every if every is not None else telemetry_every(c, record_s)
        self.silence_s = silence_s
        self.tail: list[dict] = []      # what arrived after the last hold, read when the stream stopped
        self._kept_us: int | None = None    # the board's time_us at the last HEARTBEAT sent

    def __enter__(self) -> "BoardTime":
        self.client.take_telemetry()
        self.client.set_telemetry(self.every)
        return self

    def __exit__(self, *exc: object) -> None:
        c = self.client
        c.set_telemetry(0)
        c.pump(0.05)
        self.tail = c.take_telemetry()

    def hold(self, seconds: float, on_record: Callable[[dict], None] | None = None,
             until: Callable[[dict], bool] | None = None,
             trigger: tuple[float, Callable[[], None]] | None = None,
             on_progress: Callable[[float], None] | None = None) -> list[dict]:
        """The records from now until they span ``seconds`` of board time, or
        until ``until(record)`` is true for one (the last one returned).
        Records the board sent before this call (sampled before whatever the
        caller just commanded) are dropped."""
        c = self.client
        c.take_telemetry()
        records: list[dict] = []
        span = 0.0
        last_keep = last_new = time.monotonic()
        while span < seconds:
            c.pump(0.02)
            new = c.take_telemetry()
            now = time.monotonic()
            if new:
                last_new = now
                for r in new:
                    records.append(r)
                    span = board_s(records[0]["time_us"], r["time_us"])
                    if self._kept_us is None:
                        self._kept_us = r["time_us"]
                    if on_record:
                        on_record(r)
                    if trigger and span >= trigger[0]:
                        trigger[1]()
                        trigger = None
                    if until is not None and until(r):
                        return records
            elif now - last_new > self.silence_s:
                raise ProtocolError(f"no telemetry for {now - last_new:.0f} s (board streaming every "
                                    f"{self.every} periods was requested); check `torqueloop info` counters")
            # the watchdog counts the board's time: a board faster than the host's clock (an
            # in-process simulation) is fed by its own time too, across holds
            board = records[-1]["time_us"] if records else None
            if now - last_keep > KEEPALIVE_S or (board is not None and self._kept_us is not None and
                                                  board_s(self._kept_us, board) > KEEPALIVE_S):
                c.heartbeat()
                last_keep, self._kept_us = now, board
            if on_progress:
                on_progress(span)
        return records
