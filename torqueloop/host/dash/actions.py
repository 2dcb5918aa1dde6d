# SPDX-License-Identifier: MIT
"""What a dashboard page may ask, in physical units, carried out through
the session server (torqueloop/host/serve.py): the same serialised commands
on the same authenticated session as every CLI client's, and the same
holding of axes (a page that enables, moves or drives an axis holds it; when
the last holder goes away the server disables the axis).

Each method runs in a worker thread of the web server (a board command
blocks) and returns what the page shows, or raises an exception whose
message is one line for a person."""

from __future__ import annotations

import threading
from dataclasses import dataclass
from typing import Any

import numpy as np

from torqueloop.spec import protocol as P
from torqueloop.spec import units

from .. import drive as hdrive
from ..analysis import in_unit, step_figures
from ..client import describe_faults, decode_faults
from ..serve import SessionServer
from ..session import HOMED, Session, board_s
from .hub import AXIS_FIELDS, ROW, Hub

#: the parameters the page lists, by their friendly names (units.py is their one definition)
PARAM_NAMES: tuple[str, ...] = ("law", *units.FRIENDLY, "pwm_freq")
STEP_PRE_S = 0.2            # a step test's samples before the step


@dataclass(eq=False)
class PageConn:
    """A page as a client of the session server (holds axes like a CLI client)."""
    name: str
    every: int = 0
    alive: bool = True

    def send(self, obj: dict) -> None:       # telemetry reaches pages through the hub
        pass


def _axis(axis: Any) -> int:
    a = int(axis)
    if not 0 <= a < P.AXIS_COUNT:
        raise ValueError(f"axis {axis}: 0..{P.AXIS_COUNT - 1}")
    return a


class Actions:
    def __init__(self, srv: SessionServer, hub: Hub) -> None:
        self.srv, self.hub = srv, hub
        self.clk = int((srv.identity or {}).get("clk_hz", units.CLK_HZ))
        self._mech: dict[int, units.Mechanics] = {}
        self._drive_timers: dict[int, threading.Timer] = {}
        self._limits: dict[int, int] = {}

    # ---- what the page needs to draw --------------------------------------------------
    def mech(self, axis: int) -> units.Mechanics:
        if axis not in self._mech:
            c = self.srv.client
            self._mech[axis] = self.srv._run(lambda: units.Mechanics(c.get_param("COUNTS_PER_REV", axis),
                                                                     c.get_param("PITCH_UM", axis)))
        return self._mech[axis]

    def scales(self) -> list[dict[str, float]]:
        """Per axis, a position unit's size in counts^-1: value_in_unit = counts * scale."""
        return [{u: self.mech(a).from_counts(1.0, u) for u in units.POSITION_UNITS} for a in range(P.AXIS_COUNT)]

    def status(self) -> list[dict]:
        out = []
        for a in range(P.AXIS_COUNT):
            s = self.srv.m_status(None, a)
            out.append({"enabled": bool(s["enabled"]), "moving": bool(s.get("moving", 0)),
                        "home": P.HOME_STATE.get(s["home"], "?"), "faults": decode_faults(s["faults"]),
                        "fault_words": describe_faults(s["faults"]), "position": s["position"],
                        "setpoint": s["setpoint"], "cmd_limit": self._cmd_limit(a)})
        return out

    def _cmd_limit(self, axis: int) -> int:
        """CMD_LIMIT, read once and again after the page sets it (a CLI client's change shows after a restart)."""
        if axis not in self._limits:
            self._limits[axis] = self.srv._run(lambda: self.srv.client.get_param("CMD_LIMIT", axis))
        return self._limits[axis]

    # ---- commands ---------------------------------------------------------------------
    def stop(self, conn: PageConn, **_: Any) -> str:
        """Every axis: disabled (the bridge off at once), then STOP (no profile
        left to resume).  Neither needs the key, so this works for a watcher too."""
        mask = (1 << P.AXIS_COUNT) - 1
        self._cancel_drives()
        self.srv.m_enable(conn, mask, False)
        self.srv.m_stop(conn, mask)
        return "stopped: every axis disabled"

    def enable(self, conn: PageConn, axis: Any, on: Any = True, **_: Any) -> str:
        a = _axis(axis)
        if not on:
            self._cancel_drives(a)
        self.srv.m_enable(conn, 1 << a, bool(on))
        return f"axis {a} {'enabled' if on else 'disabled'}"

    def clear_fault(self, conn: PageConn, axis: Any, **_: Any) -> str:
        a = _axis(axis)
        left = self.srv.m_clear_fault(conn, 1 << a)
        return f"axis {a}: faults left: {describe_faults(left[a])}"

    def home(self, conn: PageConn, axis: Any, mode: str = "here", **_: Any) -> str:
        a = _axis(axis)
        if mode not in P.HOME_MODES:
            raise ValueError(f"home mode {mode!r}: one of {', '.join(P.HOME_MODES)}")
        self.srv.m_home(conn, a, mode)
        return f"axis {a}: homing ({mode})" if mode != "here" else f"axis {a}: homed here"

    def _target(self, axis: int, text: str, unit: str) -> int:
        if unit not in units.POSITION_UNITS:
            raise ValueError(f"unit {unit!r}: one of {', '.join(units.POSITION_UNITS)}")
        return units.parse_position(str(text), self.mech(axis), unit)

    def move(self, conn: PageConn, axis: Any, target: str, unit: str = "mm", relative: bool = False,
             trapezoid: bool = False, unhomed: bool = False, **_: Any) -> str:
        """A move that enables its axis when it is not (MOVE's rule checked first, as the CLI's --enable)."""
        a = _axis(axis)
        counts = self._target(a, target, unit)

        def go() -> int:
            st = self.srv.client.status(a)
            t = counts + (st["position"] if relative else 0)
            Session(self.srv.client).move(a, t, bool(trapezoid), bool(unhomed), enable=True, st=st)
            return t
        t = self.srv._run(go)
        self.srv._hold(conn, 1 << a)
        return f"axis {a} -> {self.mech(a).from_counts(t, unit):.4g} {unit} ({t} counts)"

    def drive(self, conn: PageConn, axis: Any, duty: str, seconds: Any = 2.0, **_: Any) -> str:
        """Open loop at ``duty`` (percent, signed) for ``seconds``, then disabled."""
        a = _axis(axis)
        pct = hdrive.parse_duty(str(duty))
        secs = float(seconds)
        if not 0.05 <= secs <= 60:
            raise ValueError(f"drive for {seconds} s: between 0.05 and 60 s")
        steps = hdrive.steps_for(pct)

        def go() -> None:
            hdrive.check_ready(self.srv.client, a, steps)
            self.srv.client.enable(1 << a, True)
        self.srv._run(go)
        self.srv._hold(conn, 1 << a)
        try:
            self.srv.m_drive(conn, a, steps)
        except Exception:
            self.srv.m_enable(conn, 1 << a, False)
            raise
        self._cancel_drives(a)
        t = threading.Timer(secs, lambda: self._end_drive(conn, a))
        t.daemon = True
        self._drive_timers[a] = t
        t.start()
        return f"axis {a}: open loop {pct:+g}% ({steps} steps) for {secs:g} s"

    def _end_drive(self, conn: PageConn, axis: int) -> None:
        self._drive_timers.pop(axis, None)
        try:
            self.srv.m_enable(conn, 1 << axis, False)
        except Exception as e:               # the server logs; the axis's holder leaving disables it too
            self.srv.log(f"dashboard: could not end the drive of axis {axis}: {e}")

    def _cancel_drives(self, axis: int | None = None) -> None:
        for a in list(self._drive_timers):
            if axis is None or a == axis:
                self._drive_timers.pop(a).cancel()

    def step(self, conn: PageConn, axis: Any, target: str, unit: str = "mm", duration: Any = 3.0,
             unhomed: bool = False, **_: Any) -> dict:
        """Step test: a step MOVE to ``target`` (relative to where the axis is),
        ``duration`` s of telemetry, the figures (torqueloop.spec.metrics); the
        axis is disabled again if the test enabled it."""
        a = _axis(axis)
        span = float(duration)
        if not 0.2 <= span <= 60:
            raise ValueError(f"step test of {duration} s: between 0.2 and 60 s")
        step = self._target(a, target, unit)
        st = self.srv.m_status(conn, a)
        if st["faults"]:
            raise ValueError(f"axis {a} has latched faults: {describe_faults(st['faults'])}; clear them first")
        start = st["position"]
        goal = start + step
        unhomed = bool(unhomed) or st["home"] != HOMED
        was_enabled = bool(st["enabled"])
        sess = Session(self.srv.client)
        self.srv._run(lambda: sess.check_move(a, goal, False, unhomed, st, enabling=not was_enabled))
        if not was_enabled:
            self.srv.m_enable(conn, 1 << a, True)
        try:
            seq0 = self.hub.seq
            self.hub.wait_rows(seq0, lambda rows: _span_s(rows) >= STEP_PRE_S, STEP_PRE_S + 5)
            seq_step = self.hub.seq
            self.srv.m_move(conn, a, goal, False, unhomed)
            rows = self.hub.wait_rows(seq_step, lambda rows: _span_s(rows) >= span, span + 10)
        finally:
            if not was_enabled:
                self.srv.m_enable(conn, 1 << a, False)
        if len(rows) < 3:
            raise ValueError("the step test got no telemetry (is the board streaming?)")
        i_pos, i_sp = ROW.index(f"position{a}"), ROW.index(f"setpoint{a}")
        us = np.array([r[2] for r in rows], dtype=np.int64)
        t = np.concatenate([[0], np.cumsum(np.diff(us) % (1 << 32))]) / 1e6
        x = np.array([r[i_pos] for r in rows], dtype=float)
        sp = np.array([r[i_sp] for r in rows], dtype=float)
        fig = step_figures(t, x, sp, start, goal)
        out = in_unit(fig, self.mech(a), unit)
        out.update(axis=a, first_seq=rows[0][0], last_seq=rows[-1][0], records=len(rows))
        return {k: (None if isinstance(v, float) and not np.isfinite(v) else v) for k, v in out.items()}

    # ---- parameters -------------------------------------------------------------------
    def params(self, conn: PageConn, axis: Any = 0, **_: Any) -> list[dict]:
        a = _axis(axis)
        c = self.srv.client
        out = []
        for name in PARAM_NAMES:
            param, kind = units.resolve(name)
            p = P.PARAMS[param]
            raw = self.srv._run(lambda: c.get_param(param, a))
            val, unit = units.from_raw(name, raw, self.clk)
            out.append({"name": name, "param": param, "value": val, "unit": unit, "raw": raw,
                        "global": p.scope == "global", "range": self._range(name, kind, p),
                        "help": units.FRIENDLY[name].help if name in units.FRIENDLY else
                        {"law": "control law: off, p, pd, pid", "pwm_freq": "PWM carrier, eq. (4)"}[name]})
        return out

    def _range(self, name: str, kind: str, p: Any) -> str:
        if kind == "special":
            if name == "law":
                return " | ".join(units.LAWS)
            lo, hi = sorted((units.from_raw(name, p.min, self.clk)[0], units.from_raw(name, p.max, self.clk)[0]))
            return f"{lo:g} .. {hi:g} Hz"
        fr = units.FRIENDLY[name]
        return f"{p.min / fr.scale:g} .. {p.max / fr.scale:g} {fr.unit}".rstrip()

    def set_param(self, conn: PageConn, name: str, value: str, axis: Any = 0, **_: Any) -> str:
        a = _axis(axis)
        if name not in PARAM_NAMES:
            raise ValueError(f"parameter {name!r}: not one the dashboard sets")
        fr = units.FRIENDLY.get(name)
        mech = self.mech(a) if fr is not None and fr.dim is not None else None
        param, raw = units.to_raw(name, str(value), self.clk, mech)
        stored = self.srv.m_set_param(conn, param, raw, a)
        if param in ("COUNTS_PER_REV", "PITCH_UM"):
            self._mech.pop(a, None)
        self._limits.pop(a, None)
        val, unit = units.from_raw(name, stored, self.clk)
        return f"axis {a}: {name} = {val} {unit}".rstrip() + f" ({param} = {stored})"

    def save(self, conn: PageConn, **_: Any) -> str:
        r = self.srv.m_save(conn)
        return f"saved on the board (copy {r.get('seq')}); it starts with these parameters"

    OPS = ("stop", "enable", "clear_fault", "home", "move", "drive", "step", "params", "set_param", "save")

    def run(self, conn: PageConn, op: str, params: dict) -> Any:
        if op not in self.OPS:
            raise ValueError(f"unknown request {op!r}")
        return getattr(self, op)(conn, **params)


def _span_s(rows: list[list]) -> float:
    if len(rows) < 2:
        return 0.0
    return board_s(rows[0][2], rows[-1][2])


__all__ = ["Actions", "PageConn", "PARAM_NAMES", "AXIS_FIELDS"]
