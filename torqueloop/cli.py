# SPDX-License-Identifier: MIT
"""``torqueloop``: tune, move, plot and upload firmware over serial, WiFi
or the simulated board.  docs/host.md is the user's guide.

    torqueloop sim                                   # simulated board on socket://127.0.0.1:2000
    torqueloop -u socket://127.0.0.1:2000 info
    torqueloop set kp 0.82 ; torqueloop step-test 6.28rad --out build/step

The link URL comes from ``--url`` or ``$TORQUELOOP_URL``; the link key from
the file ``--key-file`` or ``$TORQUELOOP_KEY_FILE`` names (never the command
line itself; docs/security.md).  When ``torqueloop serve`` runs for that
board (or ``--server ADDR`` / ``$TORQUELOOP_SERVER`` names one), every
command goes through it instead: the server holds the link and the key.
Every command can print ``--json`` for scripts.  Exit status: 0 done, 1
refused by the board in its state, a fault during the command, or a missing,
unreadable or wrong key, 2 bad input (a value refused before anything was
sent or by the board's rules, one line naming the rule, never a traceback),
3 no answer (nothing listening, the
connection refused or closed, no reply), 130 interrupted (Ctrl-C or SIGTERM:
the axes disabled first).
"""

from __future__ import annotations

import argparse
import contextlib
import json
import math
import os
import re
import signal
import sys
import threading
import time
from pathlib import Path
from typing import Any, Callable

import torqueloop
from torqueloop.spec import auth
from torqueloop.spec import protocol as P
from torqueloop.host import analysis
from torqueloop.spec import units
from torqueloop.spec.pwm import carrier_hz
from torqueloop.host import config as hconfig
from torqueloop.host import drive as hdrive
from torqueloop.host.client import (Client, CommandRejected, LinkClosed, NoAnswer, ProtocolError, decode_faults,
                                    describe_faults, key_missing)
from torqueloop.host import serve as hserve
from torqueloop.host.remote import RemoteClient
from torqueloop.host.session import HOMED, HOMING, KEEPALIVE_S, Session
from torqueloop.host.transport import DEFAULT_BAUD, LinkOpenError, open_link
from torqueloop.host.upload import ImageRefused
from torqueloop.spec.units import BadValue

DEFAULT_URL = "socket://127.0.0.1:2000"
#: what to do about a refusal, by its rule (protocol.toml [[refusal]] says what the rule is)
REFUSAL_HINT = {
    "DISABLED": "add --enable: the command enables the axis itself and keeps the link watchdog fed",
    "FAULT": "`torqueloop status` names the fault; remove its cause, then `torqueloop clear-fault`",
    "NOT_HOMED": "`torqueloop home neg` (or pos; `home here` without switches) first, or --unhomed to "
                 "move relative to where it was at power-up",
    "FOLLOW": "use --trapezoid, a smaller step, or raise follow_limit",
    "LIMIT": "only moves away from that end",
    "CARRIER": "lower pwm_freq (a larger FDIV), or raise PWM_MAX_HZ within the bridge's rating",
    "GAIN": f"the largest physical gain is {P.PARAMS['KP_UNM_RAD'].max / 1e6:g} N m/rad",
    "PW_ORDER": "set the other end first",
    "SOFT_ORDER": "set the other end first",
    "NO_SWITCHES": "`torqueloop home here`",
    "AXES_ENABLED": "`torqueloop disable --all` first",
    "HAS_SWITCHES": "`torqueloop home neg` or `pos`; without switches `torqueloop set limit_sw 0` first",
    "HOME_POS_FROZEN": "`torqueloop disable --all` first",
    "CAUSE": "`torqueloop status` shows what is still present",
}


class Ctx:
    def __init__(self, args: argparse.Namespace) -> None:
        self.args = args
        self._client: Client | RemoteClient | None = None
        self.shared = False                       # the client belongs to a shell: leave it open
        self.tick: Callable[[], None] = lambda: None

    def server(self) -> str | None:
        """The address of the ``torqueloop serve`` the commands go through, or None (a link of their own)."""
        if getattr(self.args, "no_server", False):
            return None
        return self.args.server or os.environ.get(hserve.SERVER_ENV) or hserve.find_server(self.args.url)

    def key(self) -> tuple[bytes | None, str, str]:
        """(key, where it came from, why there is none).  A missing or bad key
        file is not an error yet: reading, stop and disable need no key."""
        path = auth.key_file_path(self.args.key_file)
        if path is None:
            return None, "", "no key file named"
        src = f"{path} ({'--key-file' if self.args.key_file else '$' + auth.KEY_FILE_ENV})"
        try:
            return auth.read_key_file(path), src, ""
        except auth.KeyFileError as e:
            return None, src, str(e)

    def require_key(self, command: str, **fields: int) -> None:
        """A command that changes the machine (auth.needs_key) is refused here,
        before the link is opened, when the tool has no usable key."""
        if auth.needs_key(command, fields) and self.server() is None:   # a server holds its own key
            key, _, err = self.key()
            if key is None:
                raise key_missing(command, err)

    @property
    def session(self) -> Session:
        return Session(self.client)

    @property
    def client(self) -> Client | RemoteClient:
        if self._client is None and (addr := self.server()):
            self._client = RemoteClient(addr, timeout=max(5.0, self.args.timeout))
        if self._client is None:
            key, src, err = self.key()
            link, info = open_link(self.args.url, self.args.baud)
            self._client = Client(link, info, timeout=self.args.timeout, retries=self.args.retries, key=key,
                                  key_source=src, key_error=err)
            self._client.connect()
        return self._client

    def mech(self, axis: int) -> units.Mechanics:
        c = self.client
        return units.Mechanics(c.get_param("COUNTS_PER_REV", axis), c.get_param("PITCH_UM", axis))

    def out(self, obj: Any, text: str | Callable[[], str]) -> None:
        if self.args.json:
            print(json.dumps(obj, default=_jsonable))
        else:
            print(text() if callable(text) else text)

    def close(self) -> None:
        if self._client is not None and not self.shared:
            self._client.close()

    def interrupted(self) -> str:
        """Ctrl-C (or SIGTERM) cut the command short: nothing it set moving
        keeps moving.  On the board's own link this process is the board's one
        client, so every enabled axis is this session's: they are disabled now,
        not left to the link watchdog (which lets them run LINK_TIMEOUT_MS on
        and latches a LINK fault).  Through a server, closing the connection
        makes the server disable the axes this command held.  Returns what
        was done, for the one line the user sees."""
        c = self._client
        if c is None:
            return "nothing had been sent to the board"
        if isinstance(c, RemoteClient):
            return "the server disables the axes this command held"
        try:
            c.enable((1 << P.AXIS_COUNT) - 1, False)
        except (ProtocolError, OSError) as e:
            return f"could not disable the axes ({e}); the board's link watchdog disables them"
        return "every axis disabled"


def _jsonable(o: Any) -> Any:
    if isinstance(o, float) and math.isnan(o):
        return None
    if hasattr(o, "tolist"):
        return o.tolist()
    return str(o)


def direct_client(ctx: "Ctx", what: str) -> Client:
    """The board's own link, for commands that cannot go through a server."""
    if ctx.server() is not None:
        raise ProtocolError(f"{what} needs the board's link to itself, and a torqueloop server "
                            f"({ctx.server()}) holds it: stop `torqueloop serve` first, or --no-server")
    c = ctx.client
    assert isinstance(c, Client)
    return c


def _axes(args: argparse.Namespace) -> list[int]:
    return list(range(P.AXIS_COUNT)) if getattr(args, "all", False) else [args.axis]


def _mask(axes: list[int]) -> int:
    return sum(1 << a for a in axes)


def _unit_out(args: argparse.Namespace, default: str) -> str:
    """The unit a command prints positions in: its --unit, else ``default``."""
    return getattr(args, "unit", None) or default


def progress(done: float, total: float, label: str, width: int = 30) -> None:
    """A plain-text progress bar on stderr (stays off stdout so --json stays clean)."""
    frac = 0.0 if total <= 0 else max(0.0, min(1.0, done / total))
    n = int(frac * width)
    sys.stderr.write(f"\r{label} [{'#' * n}{'.' * (width - n)}] {frac * 100:5.1f} %")
    if frac >= 1.0:
        sys.stderr.write("\n")
    sys.stderr.flush()


# ---- commands -------------------------------------------------------------------

def cmd_info(ctx: Ctx) -> int:
    c = ctx.client
    ident = dict(c.identity or c.identify())
    cnt = c.counters()
    obj = {"url": ctx.args.url, "proto_version": ident["proto_version"],
           "fw_version": f"{ident['fw_version'] >> 8}.{ident['fw_version'] & 0xFF}",
           "build_id": f"0x{ident['build_id']:08x}", "axis_count": ident["axis_count"],
           "clk_hz": ident["clk_hz"], "board_counters": {k: v for k, v in cnt.items() if k != "status"},
           "host_counters": {k: v for k, v in vars(c.stats).items() if k != "text_sample"}}
    ctx.out(obj, lambda: "\n".join([
        f"board at {obj['url']}: firmware {obj['fw_version']}, build id {obj['build_id']}, "
        f"protocol {obj['proto_version']}, {obj['axis_count']} axes, clock {obj['clk_hz'] / 1e6:g} MHz",
        "board link counters: " + ", ".join(f"{k} {v}" for k, v in obj["board_counters"].items()),
        f"this session: {c.stats.replies} replies, {c.stats.crc_errors} CRC errors, "
        f"{c.stats.bad_chunks} damaged chunks, {c.stats.retries} retries"]))
    return 0


def _status_text(a: int, s: dict[str, int], mech: units.Mechanics, unit: str) -> str:
    pos = mech.from_counts(s["position"], unit)
    sp = mech.from_counts(s["setpoint"], unit)
    lim = [k for k, bit in P.LIMIT_BITS.items() if s["limits"] & bit]
    return (f"axis {a}: {'ENABLED' if s['enabled'] else 'disabled'}{', moving' if s['moving'] else ''}, "
            f"{P.HOME_STATE.get(s['home'], '?')}"
            f"{' (positions relative to power-up)' if s['home'] != HOMED else ''}; "
            f"position {s['position']} counts ({pos:.4f} {unit}), set-point {s['setpoint']} ({sp:.4f} {unit}), "
            f"velocity {s['velocity_q8'] / 256:.1f} counts/s, PWM {s['pwm_cmd']}; "
            f"limit switches open: {', '.join(lim) or 'none'}; "
            f"faults: {describe_faults(s['faults'])}; link errors seen by the board: {s['rx_errors']}")


def _timing_text(s: dict[str, int]) -> str:
    """The board's control timing since power-up (the same in every axis's STATUS)."""
    over = s["overruns"]
    return (f"control timing since power-up: worst iteration {s['loop_cycles_max']} cycles, worst interrupt "
            f"lateness {s['jitter_cycles_max']} cycles, "
            + (f"{over} control periods OVERRUN (skipped: the iteration needs more than PERIOD_US; lengthen it)"
               if over else "no control period overrun"))


def _store_text(r: dict[str, int] | None) -> str:
    """What the board's parameter store says about the running parameters (SAVE op 0)."""
    if r is None:
        return "parameters: this firmware cannot store them (RAM only: lost at power-off and upload)"
    if not r["saved"]:
        return "parameters: none saved on the board (it starts with the defaults): `torqueloop save` keeps these"
    if r["differs"]:
        return (f"parameters: DIFFER from the saved copy {r['seq']} (the board starts with that one): "
                "`torqueloop save` keeps the running ones")
    return f"parameters: as saved on the board (copy {r['seq']})"


def _store_json(r: dict[str, int] | None) -> dict[str, Any] | None:
    return None if r is None else {"saved": bool(r["saved"]), "differs": bool(r["differs"]), "seq": r["seq"]}


def cmd_status(ctx: Ctx) -> int:
    res = {}
    lines = []
    report = ctx.client.store_report()
    store = _store_json(report)
    for a in _axes(ctx.args):
        s = ctx.client.status(a)
        s = {k: v for k, v in s.items() if k != "status"}
        s["fault_names"] = decode_faults(s["faults"])
        s["home_state"] = P.HOME_STATE.get(s["home"], "?")
        s["saved_parameters"] = store
        res[a] = s
        lines.append(_status_text(a, s, ctx.mech(a), ctx.args.unit))
    if res:
        lines.append(_timing_text(s))
    lines.append(_store_text(report))
    ctx.out(res, "\n".join(lines))
    return 0


def cmd_save(ctx: Ctx) -> int:
    ctx.require_key("SAVE", op=1)
    c = ctx.client
    on = [a for a in range(P.AXIS_COUNT) if c.status(a)["enabled"]]
    if on:
        raise ProtocolError(f"axes {on} are enabled: the board stores its parameters only with every axis "
                            "disabled (a save stalls the link for the flash's erase): `torqueloop disable --all`")
    r = c.save()
    ctx.out(_store_json(r), f"saved: the board starts with these parameters from now on (copy {r['seq']})")
    return 0


def cmd_get(ctx: Ctx) -> int:
    a = ctx.args
    names = a.names or [p.name for p in P.PARAMS.values()]
    clk = (ctx.client.identity or {}).get("clk_hz", units.CLK_HZ)
    res: dict[str, Any] = {}
    lines = []
    for name in names:
        param, _ = units.resolve(name)
        raw = ctx.client.get_param(param, a.axis)
        val, unit = units.from_raw(name, raw, clk)
        res[name] = {"value": val, "unit": unit, "param": param, "raw": raw}
        lines.append(f"{name} = {val} {unit}".rstrip() + (f"   ({param} = {raw})" if param != name else ""))
    ctx.out(res, "\n".join(lines))
    return 0


def cmd_set(ctx: Ctx) -> int:
    a = ctx.args
    units.to_raw(a.name, a.value, nearest=True)   # a bad value is refused before the link is opened
    ctx.require_key("SET_PARAM")
    clk = (ctx.client.identity or {}).get("clk_hz", units.CLK_HZ)
    fr = units.FRIENDLY.get(a.name.lower())
    mech = ctx.mech(a.axis) if fr is not None and fr.dim is not None else None
    param, raw = units.to_raw(a.name, a.value, clk, mech, a.nearest)
    if param == "BAUD_DIV":
        print("warning: the board changes its baud rate after this reply; reconnect with --baud",
              file=sys.stderr)
    try:
        stored = ctx.client.set_param(param, raw, a.axis)
    except CommandRejected as e:
        if e.rule == "CARRIER" and param == "FDIV":
            e.args = (f"{e} (FDIV {raw}: {carrier_hz(raw, clk):.0f} Hz; PWM_MAX_HZ "
                      f"{ctx.client.get_param('PWM_MAX_HZ')} Hz)",)
        raise
    val, unit = units.from_raw(a.name, stored, clk)
    obj = {"name": a.name, "param": param, "raw": stored, "value": val, "unit": unit}
    text = f"{a.name} = {val} {unit}   ({param} = {stored})"
    if param == "FDIV" and a.name.lower() == "pwm_freq":
        obj["requested"] = units.number(a.value.lower().removesuffix("hz").strip(), a.name)
        text = f"pwm_freq: requested {obj['requested']:g} Hz, stored {val} Hz   (FDIV = {stored})"
    ctx.out(obj, text)
    return 0


def cmd_enable(ctx: Ctx, on: bool) -> int:
    axes = _axes(ctx.args)
    ctx.require_key("ENABLE", enable=int(on))
    ctx.client.enable(_mask(axes), on)
    ctx.out({"axes": axes, "enabled": on}, f"axes {axes} {'enabled' if on else 'disabled'}")
    if on and not ctx.args.json:
        timeout = ctx.client.get_param("LINK_TIMEOUT_MS")
        print(f"note: an enabled axis stays enabled only while a host keeps commanding it: the board "
              f"disables it after {timeout} ms without a command (LINK fault), and a `torqueloop serve` "
              "disables it when this command ends. To move, `move TARGET --enable --wait S` and "
              "`home neg` enable the axis themselves and disable it when done; "
              "`torqueloop shell` keeps it enabled between commands", file=sys.stderr)
    return 0


def _hold(ctx: Ctx, axis: int) -> int:
    """--hold: keep ``axis`` enabled, feeding the link watchdog, until Ctrl-C or
    a fault; then disable it.  Returns the exit status (1 after a fault)."""
    c = ctx.client
    print(f"holding axis {axis} (Ctrl-C disables it and ends)", file=sys.stderr, flush=True)
    rc = 0
    try:
        while True:
            c.heartbeat()
            s = c.status(axis)
            if s["faults"] or not s["enabled"]:
                print(f"axis {axis} {'faulted: ' + describe_faults(s['faults']) if s['faults'] else 'was disabled'}",
                      file=sys.stderr)
                rc = 1
                break
            time.sleep(KEEPALIVE_S)
    except KeyboardInterrupt:
        pass
    finally:
        c.enable(1 << axis, False)
    return rc


SETTLE_HOLD_S = 0.3   # "settled": the profile done and the position within the tolerance this long


def _wait_settled(ctx: Ctx, axis: int, limit_s: float, tol: int, start: int, target: int
                  ) -> tuple[dict[str, int], bool]:
    """Poll until the axis has settled - its profile done and its position
    within ``tol`` counts of the set-point for SETTLE_HOLD_S, as a settling
    time is defined - or ``limit_s`` has passed, feeding the link watchdog;
    (status, settled)."""
    c = ctx.client
    t0 = time.monotonic()
    span = abs(target - start)
    shown = False
    inside_since: float | None = None
    try:
        while True:
            s = c.status(axis)
            now = time.monotonic()
            if s["faults"]:
                raise ProtocolError(f"axis {axis} faulted during the move: {describe_faults(s['faults'])}")
            if not s["moving"] and abs(s["setpoint"] - s["position"]) <= tol:
                inside_since = now if inside_since is None else inside_since
                if now - inside_since >= SETTLE_HOLD_S:
                    return s, True
            else:
                inside_since = None
            if now - t0 > limit_s:
                return s, False
            if not ctx.args.json and span:      # how much of the way it has come, not of the wait
                progress(span - min(span, abs(target - s["position"])), span, f"axis {axis} moving")
                shown = True
            c.heartbeat()
            ctx.tick()
            time.sleep(KEEPALIVE_S)
    finally:
        if shown:
            sys.stderr.write("\n")


def cmd_move(ctx: Ctx) -> int:
    a = ctx.args
    units.parse_position(a.target, units.Mechanics(), a.unit or "counts")   # refused before the link is opened
    ctx.require_key("MOVE")
    mech = ctx.mech(a.axis)
    target = units.parse_position(a.target, mech, a.unit or "counts")
    st = ctx.client.status(a.axis)
    if a.relative:
        target += st["position"]
        if not units.INT32_MIN <= target <= units.INT32_MAX:
            raise BadValue(f"{a.target} from {st['position']} is beyond the encoder's 32-bit range")
    ctx.session.move(a.axis, target, a.trapezoid, a.unhomed, enable=a.enable, st=st)
    res: dict[str, Any] = {"axis": a.axis, "target_counts": target, "mode": "trapezoid" if a.trapezoid else "step"}
    shown = _unit_out(a, "counts")
    text = f"axis {a.axis} -> {target} counts" + ("" if shown == "counts" else
                                                  f" ({mech.from_counts(target, shown):.4f} {shown})")
    rc = 0
    if a.wait:
        try:
            s, settled = _wait_settled(ctx, a.axis, a.wait, a.tolerance, st["position"], target)
        except ProtocolError:
            if not a.hold:
                ctx.client.enable(1 << a.axis, False)
            raise
        res.update(position_counts=s["position"], error_counts=target - s["position"], settled=settled)
        text += (f"; {'settled' if settled else 'not settled'} at {s['position']} counts "
                 f"(error {target - s['position']}, tolerance {a.tolerance})")
        if not settled:
            text += f" after {a.wait:g} s"
            rc = EXIT_REFUSED
    if a.wait and not a.hold:
        ctx.client.enable(1 << a.axis, False)
        res["disabled"] = True
        text += f"; axis {a.axis} disabled (--hold keeps it enabled)"
    ctx.out(res, text)
    if a.hold:
        return _hold(ctx, a.axis) or rc
    if not a.wait and not a.json and ctx.server() is None:
        print(f"note: without --wait or --hold this command ends now, and the board disables axis {a.axis} "
              "after LINK_TIMEOUT_MS without a command (LINK fault)", file=sys.stderr)
    return rc


def cmd_home(ctx: Ctx) -> int:
    a = ctx.args
    ctx.require_key("HOME")
    c = ctx.client
    # Homing moves the soft-limit window, so the board takes it only with every axis disabled,
    # and homing to a switch enables its axis itself (docs/safety.md); --enable is that default.
    c.home(a.axis, a.mode, a.index)
    t0 = time.monotonic()
    while a.mode != "here" and time.monotonic() - t0 < a.wait:
        st = c.status(a.axis)
        if st["home"] != HOMING or st["faults"]:
            break
        c.heartbeat()
        ctx.tick()
        if not a.json:
            progress(time.monotonic() - t0, a.wait, f"axis {a.axis} homing")
        time.sleep(KEEPALIVE_S)
    if a.mode != "here" and not a.json:
        sys.stderr.write("\n")
    st = c.status(a.axis)
    if not a.hold and st["enabled"]:
        c.enable(1 << a.axis, False)
    obj = {"axis": a.axis, "mode": a.mode, "index": a.index, "home_state": P.HOME_STATE.get(st["home"], "?"),
           "position_counts": st["position"], "faults": decode_faults(st["faults"]),
           "enabled": bool(a.hold and st["enabled"])}
    ctx.out(obj, f"axis {a.axis}: {obj['home_state']}, position {st['position']} counts; "
                 f"faults: {describe_faults(st['faults'])}"
                 + ("" if a.hold or not st["enabled"] else f"; axis {a.axis} disabled (--hold keeps it enabled)"))
    if st["faults"]:
        return 1
    if a.mode != "here" and a.wait and st["home"] != HOMED:
        raise ProtocolError(f"axis {a.axis} still {obj['home_state']} after {a.wait:g} s "
                            f"(HOME_VEL {c.get_param('HOME_VEL', a.axis)} counts/s; --wait S waits longer)")
    if a.hold:
        return _hold(ctx, a.axis)
    return 0


def cmd_drive(ctx: Ctx) -> int:
    a = ctx.args
    percent = hdrive.parse_duty(a.duty)        # refused before the link is opened
    steps = hdrive.steps_for(percent)
    ctx.require_key("DRIVE")
    c = ctx.client
    clk = (c.identity or {}).get("clk_hz", units.CLK_HZ)
    fdiv_before = c.get_param("FDIV", a.axis)
    fdiv = fdiv_before
    if a.pwm_freq is not None:
        # the nearest carrier (as --help says); the board refuses one above PWM_MAX_HZ
        fdiv = units.to_raw("pwm_freq", str(a.pwm_freq), clk, nearest=True)[1]
    hdrive.check_ready(c, a.axis, steps)
    if fdiv != fdiv_before:
        c.set_param("FDIV", fdiv, a.axis)
    pw0, pwmax = c.get_param("PW0", a.axis), c.get_param("PWMAX", a.axis)
    mech = ctx.mech(a.axis)
    carrier = carrier_hz(fdiv, clk)
    if not a.json:
        print(f"axis {a.axis}: open-loop {percent:+g}% = {steps} steps (bridge duty "
              f"{hdrive.pin_duty(steps, pw0, pwmax):.1f}% with PW0 {pw0}, PWMAX {pwmax}) at {carrier:.1f} Hz "
              f"for {a.seconds:g} s; Ctrl-C stops", file=sys.stderr)

    def show(smp: dict) -> None:
        if not a.json:
            print(f"t {smp['t_s']:6.2f} s  count {smp['position']:9d}  speed {smp['velocity_cps']:9.1f} counts/s "
                  f"({mech.from_counts(round(smp['velocity_cps']), 'rev'):+.3f} rev/s)  pwm {smp['pwm_cmd']:5d}",
                  flush=True)

    try:
        r = hdrive.drive(c, a.axis, steps, a.seconds, on_sample=show)
    finally:
        if fdiv != fdiv_before:
            c.set_param("FDIV", fdiv_before, a.axis)
    sign = (r.moved > 0) - (r.moved < 0)
    obj = {"axis": a.axis, "duty_percent": percent, "duty_steps": steps, "pwm_freq_hz": round(carrier, 3),
           "start_counts": r.start_counts, "end_counts": r.end_counts, "moved_counts": r.moved,
           "sign_matches": sign == ((steps > 0) - (steps < 0)), "seconds": round(r.seconds, 3),
           "interrupted": r.interrupted, "faults": decode_faults(r.faults), "samples": r.samples}
    verdict = ("no motion: the duty may be inside the dead zone (raise it), or the encoder is not counting"
               if sign == 0 else ("the encoder counts the same way as the duty" if obj["sign_matches"] else
                                  "the encoder counts AGAINST the duty: swap its A/B wires (or the motor's) "
                                  "before closing the loop"))
    ctx.out(obj, f"axis {a.axis} disabled{' (Ctrl-C)' if r.interrupted else ''}: moved {r.moved:+d} counts "
                 f"({mech.from_counts(r.moved, 'mm'):+.3f} mm) in {r.seconds:.1f} s; {verdict}"
                 + (f"; FAULT {describe_faults(r.faults)}" if r.faults else ""))
    return 1 if r.faults else 0


def cmd_char_sweep(ctx: Ctx) -> int:
    from torqueloop.host import sweep

    a = ctx.args
    try:
        carriers = [float(x) for x in a.carriers.split(",")] if a.carriers else []
    except ValueError:
        raise BadValue(f"--carriers {a.carriers!r}: give Hz, comma-separated (450,200)") from None
    if any(not 0 < f < 1e7 for f in carriers):
        raise BadValue(f"--carriers {a.carriers}: every carrier must be above 0 Hz")
    if a.gauge:
        return _char_gauge_sweep(ctx)
    ctx.require_key("DRIVE")
    c = ctx.client
    clk = (c.identity or {}).get("clk_hz", units.CLK_HZ)
    if not carriers:
        carriers = [carrier_hz(c.get_param("FDIV", a.axis), clk)]

    def show(r: "sweep.Ramp") -> None:
        if a.json:
            return
        sign = "+" if r.direction > 0 else "-"
        moves = f"moves from {r.breakaway_percent:g}%" if r.breakaway_percent is not None else \
            f"does not move up to {a.max:g}%"
        stops = f", stops at {r.stop_percent:g}%" if r.stop_percent is not None else \
            f", still moving at 0% (it coasts longer than half of --hold {a.hold:g} s: a longer hold reads the stop)" \
            if r.breakaway_percent is not None and not r.fault else ""
        print(f"{r.carrier_hz:9.1f} Hz  {sign}: {moves}{stops}" + (f"  FAULT {r.fault}" if r.fault else ""),
              flush=True)

    ramps = sweep.sweep(c, a.axis, carriers, clk, log=show, start=a.start, step=a.step, stop_at=a.max,
                        hold_s=a.hold, move_counts=a.move_counts)
    rows = sweep.as_rows(ramps)
    if a.out:
        out = Path(a.out)
        out.parent.mkdir(parents=True, exist_ok=True)
        out.write_text(json.dumps({"axis": a.axis, "ramps": rows}, indent=1) + "\n")
    ctx.out({"axis": a.axis, "ramps": rows}, f"axis {a.axis}: {len(ramps)} ramps"
            + (f"; written to {a.out}" if a.out else ""))
    return 1 if any(r.fault for r in ramps) else 0


def _char_gauge_sweep(ctx: Ctx) -> int:
    """`characterize sweep --gauge DIR`: torqueloop/characterize/board.py."""
    from torqueloop.characterize import board, command
    from torqueloop.characterize.data import BenchConstants

    a = ctx.args
    if a.wheel_radius is None:
        raise BadValue("--gauge: give the rope bench's --wheel-radius in metres (docs/characterization.md)")
    try:
        freqs = tuple(float(x) for x in a.freqs.split(",")) if a.freqs else board.PAPER_FREQS_HZ
    except ValueError:
        raise BadValue(f"--freqs {a.freqs!r}: give Hz, comma-separated, increasing") from None
    if len(freqs) < 4 or any(not 0 < f < 1e7 for f in freqs) or list(freqs) != sorted(set(freqs)):
        raise BadValue(f"--freqs {a.freqs}: at least 4 carriers above 0 Hz, increasing")
    read = board.ReadingsTable.load(a.readings) if a.readings else \
        board.prompt_reader(out=sys.stderr if a.json else sys.stdout)     # --json: stdout is the JSON's
    motor = a.motor or ("x", "z")[a.axis]
    out_dir = Path(a.gauge) / motor
    ctx.require_key("DRIVE")
    clk = (ctx.client.identity or {}).get("clk_hz", units.CLK_HZ)

    def show(p) -> None:
        if not a.json:
            print(f"  {p.sweep:9s} {p.duty_pct:5.1f} % {p.carrier_hz:8.1f} Hz: "
                  + (f"FAULT {p.fault}" if p.fault else f"{p.force_n:g} N, {p.current_a:g} A, "
                                                          f"moved {p.moved_counts:+d} counts"), flush=True)

    try:
        res, points = board.run(ctx.client, a.axis, clk, out_dir, motor,
                                BenchConstants(a.wheel_radius, a.theta, a.supply_v), read, freqs_hz=freqs,
                                settle_s=a.settle, log=show)
    except board.SweepAbandoned as e:
        raise ProtocolError(f"characterize sweep --gauge: {e}; the axis is disabled, the sweeps so far in "
                            f"{out_dir}") from None
    obj = {"axis": a.axis, "motor": motor, "status": res.status, "message": res.message,
           "dir": str(out_dir), "points": len(points),
           "chosen_hz": res.chosen.freq_hz if res.chosen else None}
    ctx.out(obj, f"{motor}: {res.status}; {len(points)} settings held; sweeps in {out_dir}"
            + (f"; {res.message}" if res.message else ""))
    if res.status != "pass":
        return 1
    if a.config:
        with contextlib.redirect_stdout(sys.stderr if a.json else sys.stdout):
            return command.main(["run", str(Path(a.gauge)), "--out", a.config])
    return 0


def cmd_stop(ctx: Ctx) -> int:
    axes = _axes(ctx.args)
    ctx.client.stop(_mask(axes))
    ctx.out({"axes": axes, "stopped": True}, f"axes {axes} hold their position")
    return 0


def cmd_clear_fault(ctx: Ctx) -> int:
    axes = _axes(ctx.args)
    ctx.require_key("CLEAR_FAULT")
    before = {a: ctx.client.status(a)["faults"] for a in axes}
    f0, f1 = ctx.client.clear_fault(_mask(axes))
    after = {0: f0, 1: f1}
    ctx.out({"before": {a: decode_faults(v) for a, v in before.items()},
             "after": {a: decode_faults(after[a]) for a in axes}},
            "\n".join(f"axis {a}: cleared {', '.join(decode_faults(before[a])) or 'nothing'}; "
                      f"latched now: {describe_faults(after[a])}" for a in axes))
    return 0


def capture(ctx: Ctx, duration: float, every: int = 1, on_record: Callable[[dict], None] | None = None,
            label: str = "capture", trigger: tuple[float, Callable[[], None]] | None = None) -> list[dict]:
    """Session.capture with a progress bar (none with --json, on_record or no end)."""
    show = not ctx.args.json and on_record is None and math.isfinite(duration)
    records = ctx.session.capture(duration, every, on_record, trigger,
                                  on_progress=(lambda span: progress(span, duration, label)) if show else None,
                                  silence_s=max(5.0, 10 * ctx.args.timeout))
    if show:
        progress(duration, duration, label)
    return records


def cmd_monitor(ctx: Ctx) -> int:
    a = ctx.args
    mech = ctx.mech(a.axis)
    tty = sys.stdout.isatty() and not a.json

    def show(r: dict) -> None:
        if a.json:
            print(json.dumps(r), flush=True)
            return
        parts = [f"t {r['time_us'] / 1e6:9.3f} s"]
        for i, ax in enumerate(r["axes"]):
            parts.append(f"| ax{i} {'EN' if ax['enabled'] else '--'} pos {mech.from_counts(ax['position'], a.unit):9.4f} "
                         f"sp {mech.from_counts(ax['setpoint'], a.unit):9.4f} err {ax['error']:6d} cts "
                         f"v {ax['velocity_q8'] / 256:8.1f} cts/s pwm {ax['pwm_cmd']:5d}"
                         + (f" FAULT {','.join(decode_faults(ax['faults']))}" if ax["faults"] else ""))
        line = " ".join(parts)
        print(("\r" + line) if tty else line, end="" if tty else "\n", flush=True)

    try:
        capture(ctx, a.duration if a.duration > 0 else float("inf"), a.every, on_record=show)
    except KeyboardInterrupt:
        pass
    if tty:
        print()
    return 0


def _need_display() -> None:
    """A live window needs a display; without one, say what works instead (before the link is opened)."""
    import matplotlib

    headless = sys.platform.startswith("linux") and not (os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY"))
    if headless or matplotlib.get_backend().lower() in ("agg", "pdf", "ps", "svg", "cairo", "template"):
        raise BadValue("plot: no display for a window; `plot --save PREFIX --duration S` writes PNG and CSV, "
                       "and `torqueloop shell` plots in the terminal while moves run")


def cmd_plot(ctx: Ctx) -> int:
    a = ctx.args
    if not a.save:
        _need_display()
    mech = ctx.mech(a.axis)
    if a.save:
        records = capture(ctx, a.duration, a.every)
        cap = analysis.to_capture(records)
        png, csvp = Path(a.save).with_suffix(".png"), Path(a.save).with_suffix(".csv")
        png.parent.mkdir(parents=True, exist_ok=True)
        analysis.write_csv(csvp, cap, mech, a.unit)
        analysis.plot(png, cap, mech, a.unit, axes=_axes(a), title=f"{a.url}, {a.duration:g} s")
        ctx.out({"png": str(png), "csv": str(csvp), "records": cap.n}, f"wrote {png} and {csvp} ({cap.n} records)")
        return 0
    import matplotlib.pyplot as plt  # live window

    records: list[dict] = []
    fig = None

    def live(r: dict) -> None:
        nonlocal fig
        records.append(r)
        if len(records) % 4 == 0:
            cap = analysis.to_capture(records[-2000:])
            plt.close(fig) if fig is not None else None
            fig = analysis.plot(None, cap, mech, a.unit, axes=_axes(a))
            plt.pause(0.001)

    plt.ion()
    try:
        capture(ctx, a.duration if a.duration > 0 else float("inf"), a.every, on_record=live)
    except KeyboardInterrupt:
        pass
    return 0


def cmd_step_test(ctx: Ctx) -> int:
    a = ctx.args
    bare = a.unit or "counts"          # a bare number is counts, as everywhere (torqueloop/spec/units.py)
    a.unit = _unit_out(a, "rad")
    units.parse_position(a.target, units.Mechanics(), bare)   # refused before the link is opened
    ctx.require_key("MOVE")
    c = ctx.client
    mech = ctx.mech(a.axis)
    s0 = c.status(a.axis)
    start = s0["position"]
    target = units.parse_position(a.target, mech, bare)
    if a.relative:
        target += start
        if not units.INT32_MIN <= target <= units.INT32_MAX:
            raise BadValue(f"{a.target} from {start} is beyond the encoder's 32-bit range")
    ctx.session.check_move(a.axis, target, a.trapezoid, a.unhomed, s0, enabling=not s0["enabled"])
    if s0["faults"]:
        raise ProtocolError(f"axis {a.axis} has latched faults: {describe_faults(s0['faults'])}; "
                            "`torqueloop clear-fault` first")
    was_enabled = bool(s0["enabled"])
    if not was_enabled:
        c.enable(1 << a.axis, True)
    def go() -> None:
        c.move(a.axis, target, a.trapezoid, a.unhomed)

    try:
        # a few samples before the step show where it started from
        records = capture(ctx, a.duration + a.pre, 1, label=f"step-test axis {a.axis}", trigger=(a.pre, go))
    finally:
        if not was_enabled and not a.keep_enabled:
            c.enable(1 << a.axis, False)
    cap = analysis.to_capture(records)
    sp = cap.data["setpoint"][:, a.axis]
    moved = [k for k in range(cap.n) if sp[k] != sp[0]] if a.trapezoid else \
        [k for k in range(cap.n) if sp[k] == target]
    if not moved:
        raise ProtocolError("the capture holds no sample after the move command (telemetry lost?)")
    k0 = max(0, moved[0] - 1)   # the sample before the first that shows the move
    t = cap.t[k0:] - cap.t[k0]
    x = cap.data["position"][k0:, a.axis]
    fig = analysis.step_figures(t, x, sp[k0:], start, target, a.band / 100)
    faults = int(max(cap.data["faults"][:, a.axis]))
    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    stem = out / f"step_axis{a.axis}"
    analysis.write_csv(stem.with_suffix(".csv"), cap, mech, a.unit)
    analysis.plot(stem.with_suffix(".png"), cap, mech, a.unit, axes=[a.axis],
                  title=f"step {mech.from_counts(start, a.unit):.4g} -> {mech.from_counts(target, a.unit):.4g} "
                        f"{a.unit}, axis {a.axis}", figures=[(a.axis, fig)])
    figs = analysis.in_unit(fig, mech, a.unit)
    figs["axis"] = a.axis
    figs["faults"] = decode_faults(faults)
    figs["records"] = cap.n
    (stem.with_suffix(".json")).write_text(json.dumps(figs, indent=2, default=_jsonable) + "\n")
    ctx.out({"figures": figs, "png": str(stem.with_suffix(".png")), "csv": str(stem.with_suffix(".csv"))},
            lambda: "\n".join([
                f"step {start} -> {target} counts on axis {a.axis} ({cap.n} samples)",
                f"  overshoot      {fig.overshoot_pct:.2f} %",
                f"  rise (10-90 %) {analysis.fmt_s(fig.rise_time_s)}",
                f"  settling       {analysis.fmt_s(fig.settling_time_s)}  (band +-{fig.band:.0f} counts)",
                f"  steady state   {fig.steady_state_error:.1f} counts "
                f"({mech.from_counts(fig.steady_state_error, a.unit):.4g} {a.unit}; mean of the last 10 %)",
                f"  RMSE eq. (26)  {fig.rmse:.1f} counts ({mech.from_counts(fig.rmse, a.unit):.4g} {a.unit})",
                f"  faults         {describe_faults(faults)}",
                f"wrote {stem}.png, .csv, .json"]))
    return 0 if not faults else 1


def cmd_config(ctx: Ctx) -> int:
    a = ctx.args
    if a.action == "save":
        c = ctx.client
        ident = c.identity or c.identify()
        glob = {k: c.get_param(k) for k in hconfig.GLOBAL_PARAMS}
        axes = tuple({k: c.get_param(k, i) for k in hconfig.AXIS_PARAMS} for i in range(P.AXIS_COUNT))
        readable = {"axes": [{"kp_N_m_per_rad": c.get_param("KP_UNM_RAD", i) / 1e6,
                              "kd_N_m_s_per_rad": c.get_param("KD_UNMS_RAD", i) / 1e6,
                              "ki_N_m_per_rad_s": c.get_param("KI_UNM_RADS", i) / 1e6,
                              "pwm_freq_hz": round(carrier_hz(axes[i]["FDIV"], ident["clk_hz"]), 3)}
                             for i in range(P.AXIS_COUNT)]}
        cfg = hconfig.HostConfig(axes, glob, ident["build_id"], ident["proto_version"], "host")
        Path(a.file).write_text(hconfig.to_json(cfg, readable))
        ctx.out({"file": a.file, "build_id": f"0x{ident['build_id']:08x}"},
                f"saved {len(glob) + sum(map(len, axes))} parameters to {a.file} (build id 0x{ident['build_id']:08x})")
        return 0
    cfg = hconfig.load_file(a.file)   # the file first: a bad one needs no board
    ctx.require_key("SET_PARAM")
    c = ctx.client
    ident = c.identity or c.identify()
    warn = []
    if cfg.proto_version is not None and not P.CONFIG_SINCE <= cfg.proto_version <= ident["proto_version"]:
        raise ProtocolError(f"{a.file} was saved with protocol {cfg.proto_version}; the board speaks "
                            f"{ident['proto_version']} and reads the files of protocols {P.CONFIG_SINCE} to "
                            f"{ident['proto_version']}")
    if cfg.build_id is not None and cfg.build_id != ident["build_id"]:
        warn.append(f"saved from firmware build 0x{cfg.build_id:08x}, the board runs 0x{ident['build_id']:08x}")
        if not a.force:
            raise ProtocolError(f"{a.file}: {warn[-1]}; parameters may differ in meaning - check and use --force")
    enabled = [i for i in range(P.AXIS_COUNT) if c.status(i)["enabled"]]
    if enabled:
        raise ProtocolError(f"axes {enabled} are enabled: `torqueloop disable --all` before loading")
    writes = hconfig.apply_order(cfg)
    for n, (axis, name, value) in enumerate(writes):
        c.set_param(name, value, 0 if axis == P.GLOBAL_AXIS else axis)
        if not a.json:
            progress(n + 1, len(writes), "config load")
    final = {(ax, k): v for ax, k, v in writes}      # the last write of each parameter is what must stick
    mismatch = [(ax, k, v) for (ax, k), v in final.items() if c.get_param(k, 0 if ax == P.GLOBAL_AXIS else ax) != v]
    if mismatch:
        raise ProtocolError(f"read back differs after loading: {mismatch}")
    ctx.out({"file": a.file, "source": cfg.source, "writes": len(writes), "warnings": warn},
            f"loaded {a.file} ({cfg.source}): {len(writes)} writes, read back and checked"
            + "".join(f"\nwarning: {w}" for w in warn))
    return 0


def cmd_upload(ctx: Ctx) -> int:
    from torqueloop.host import upload

    image = upload.load_image(ctx.args.file, raw_ok=ctx.args.raw)   # before the link is opened
    before = ctx.client.store_report()
    if not ctx.args.json and (before is None or before["differs"]):
        print("note: the running parameters are not saved on the board; the new firmware starts with "
              + ("the saved copy" if before and before["saved"] else "its defaults")
              + " (`torqueloop config save FILE` or `torqueloop save` first to keep them)", file=sys.stderr)
    show = None if ctx.args.json else (lambda done, total: progress(done, total, "upload"))
    r = upload.run_upload(direct_client(ctx, "upload"), image, show, window_s=ctx.args.window)
    obj = {"ok": r.ok, "message": r.message, "bytes": r.bytes, "crc32": f"0x{r.crc32:08x}",
           "old_build_id": f"0x{r.old_build_id:08x}",
           "new_build_id": None if r.new_build_id is None else f"0x{r.new_build_id:08x}",
           "bootloader_replies": r.replies, "seconds": round(r.seconds, 3)}
    after = ctx.client.store_report() if r.new_build_id is not None else None
    obj["saved_parameters_before"] = _store_json(before)
    obj["saved_parameters"] = _store_json(after)
    ctx.out(obj, lambda: (f"upload {'done' if r.ok else 'REFUSED'}: {r.message} ({r.seconds:.1f} s)\n"
                          f"build id 0x{r.old_build_id:08x} -> {obj['new_build_id']}"
                          + (f"\n{_store_text(after)}" if r.new_build_id is not None else "")))
    return 0 if r.ok else 1


def cmd_key(ctx: Ctx) -> int:
    """Key files (docs/security.md): ``key new FILE`` writes a fresh random key
    (mode 0600, never over an existing file); ``key id [FILE]`` names a key
    without giving it away."""
    a = ctx.args
    if a.action == "new":
        if not a.file:
            raise auth.KeyFileError("key new needs the FILE to create")
        key = auth.new_key()
        folder = Path(a.file).expanduser().parent
        if not folder.exists():
            try:
                folder.mkdir(parents=True, mode=0o700)   # only its owner may list the keys
            except OSError as e:
                raise auth.KeyFileError(f"cannot create the folder {folder}: {e.strerror}") from None
        auth.write_key_file(Path(a.file).expanduser(), key)
        ctx.out({"file": a.file, "key_id": auth.key_id(key)},
                f"wrote a new link key to {a.file} (key id {auth.key_id(key)}); keep it off the network. "
                "Next: build the board's boot ROM with it (docs/security.md, 'Key provisioning')")
        return 0
    path = auth.key_file_path(a.file or a.key_file)
    if path is None:
        raise auth.KeyFileError(f"no key file named: key id FILE, --key-file FILE or ${auth.KEY_FILE_ENV}")
    key = auth.read_key_file(path)
    ctx.out({"file": str(path), "key_id": auth.key_id(key)}, f"{path}: key id {auth.key_id(key)}")
    return 0


def cmd_sim(ctx: Ctx) -> int:
    try:
        from torqueloop.sim.server import BoardServer
        from torqueloop.sim.simboard import SimBoard
        import sim_models.stepper  # noqa: F401  (the plant; SimBoard imports it when built)
        from sim_models.variants import plant_choice
    except ImportError as e:   # a host-only install (pip install torqueloop[host])
        raise SimStackMissing(f"the simulated board needs the simulation stack ({e.name} is missing): "
                              f"pip install 'torqueloop[sim]'") from None
    plant = plant_choice(ctx.args.plant, ctx.args.plant_file)   # a bad name or file: one line (a ValueError)

    a = ctx.args
    # The simulated board is provisioned with the tool's own key (the file it names)
    key, src, err = ctx.key()
    if err and src:
        raise auth.KeyFileError(err)      # a key file named but unusable: say so, do not run keyless
    keyed = (f"key id {auth.key_id(key)} from {src}" if key else
             "NO KEY: it refuses motion, parameter changes and uploads (give it one with --key-file)")
    if a.rtl:
        from torqueloop.sim.rtlboard import RtlBoard

        if a.flash:
            raise BadValue("sim --rtl --flash: the RTL co-simulation attaches no flash model to the board top's "
                           "flash block (it reads as an erased flash: save fails); --flash is the "
                           "firmware-in-the-loop board's")
        board: Any = RtlBoard(seed=a.seed, plant=plant, key=key)
        what = f"RTL board image (Verilator) + plant model, far below real time, {keyed}"
    else:
        from torqueloop.sim.epcs import Epcs
        from torqueloop.sim.simboard import FLASH_ERASE_S, FLASH_PROGRAM_S

        flash = Epcs(a.flash, program_s=FLASH_PROGRAM_S, erase_s=FLASH_ERASE_S) if a.flash else None
        board = SimBoard(build_id=a.build_id, seed=a.seed, plant=plant, key=key, flash=flash)
        if a.switches is not None:
            board.limit_counts = [(-a.switches, a.switches)] * P.AXIS_COUNT
        what = (f"servo firmware + plant model, build id 0x{board.build_id:08x}, {keyed}, "
                f"configuration flash {a.flash or 'in memory'}")
    srv = BoardServer(board, a.host, a.port, speed=a.speed, hello=a.hello)
    print(f"simulated board on socket://{a.host}:{srv.port} ({what}); Ctrl-C stops it", flush=True)
    try:
        srv.serve_forever()
    except KeyboardInterrupt:
        pass
    return 0


def cmd_serve(ctx: Ctx) -> int:
    """``torqueloop serve``: torqueloop/host/serve.py (the wire protocol is in docs/host.md)."""
    a = ctx.args
    other = a.server or os.environ.get(hserve.SERVER_ENV) or hserve.find_server(a.url)
    if other:
        raise ProtocolError(f"a torqueloop server already holds {a.url}: {other}")
    if a.http is not None:
        from torqueloop.host.dash.launch import check_http
        check_http(a.http)                # a mistyped dashboard address is refused before the board is touched
    key, src, err = ctx.key()
    if err and src:
        raise auth.KeyFileError(err)      # a key file named but unusable: say so, do not serve keyless
    a.no_server = True
    c = direct_client(ctx, "serve")
    srv = hserve.SessionServer(c, a.url, a.host, a.port,
                               log=None if a.quiet else (lambda m: print(m, file=sys.stderr, flush=True)))
    hserve.write_state(a.url, srv.addr)
    keyed = f"key id {auth.key_id(key)} from {src}" if key else "NO KEY: reading, stop and disable only"
    print(f"torqueloop server for {a.url} on {srv.addr} ({keyed}); clients: any torqueloop command "
          "on this machine, or `torqueloop shell`; Ctrl-C stops it", flush=True)
    if a.host not in ("127.0.0.1", "localhost", "::1"):
        print(f"warning: listening on {a.host}: anyone who reaches this port commands the machine "
              "without a key", file=sys.stderr)
    stop_dash = lambda: None      # noqa: E731
    if a.http is not None:
        from torqueloop.host.dash.launch import start as start_dashboard
        try:
            stop_dash = start_dashboard(srv, a.http, a.http_tokens, lambda m: print(m, flush=True))
        except BaseException:
            srv.shutdown()
            hserve.remove_state(a.url)
            raise
    signal.signal(signal.SIGTERM, lambda *_: srv.stop())     # `kill` stops it as cleanly as Ctrl-C
    try:
        srv.serve_forever()
    except KeyboardInterrupt:
        pass
    finally:
        srv.stop()
        stop_dash()
        hserve.remove_state(a.url)
    return 0


def _sweep_parser() -> argparse.ArgumentParser:
    """``torqueloop characterize sweep``: the board as the characterisation's
    PWM source (the rest of ``characterize`` is the method's own command)."""
    cs = _Parser(prog="torqueloop characterize sweep",
                 description="encoder-only dead zone: the breakaway and stop duty per direction at each carrier "
                             "(raise the duty until it moves, lower it until it stops)")
    cs.add_argument("--axis", "-a", type=int, choices=range(P.AXIS_COUNT), default=0, help="axis [0]")
    cs.add_argument("--carriers", metavar="HZ,HZ", default=None,
                    help="PWM carriers, comma-separated (each the nearest the divider makes) [the axis's own]")
    cs.add_argument("--start", type=_bounded(float, 0, 100, "--start"), default=1.0, metavar="%",
                    help="first duty of each ramp, percent [1]")
    cs.add_argument("--step", type=_bounded(float, 0.05, 50, "--step"), default=0.5, metavar="%",
                    help="duty step, percent [0.5]")
    cs.add_argument("--max", type=_bounded(float, 0.1, 100, "--max"), default=30.0, metavar="%",
                    help="highest duty tried, percent (at most CMD_LIMIT) [30]")
    cs.add_argument("--hold", type=_bounded(float, 0.05, 60, "--hold"), default=0.3, metavar="S",
                    help="seconds at each duty (keep it under STALL_MS above STALL_CMD) [0.3]")
    cs.add_argument("--move-counts", type=_bounded(int, 1, 1_000_000, "--move-counts"), default=3, metavar="N",
                    help="counts in the duty's direction during a hold that mean 'it moves' [3]")
    cs.add_argument("--out", metavar="FILE", default=None, help="write the ramps as JSON")
    g = cs.add_argument_group("with a force gauge (--gauge): the method's own sweeps, the board as the PWM source")
    g.add_argument("--gauge", metavar="DIR", default=None,
                   help="hold each setting of steps 2-6 and take the gauge's force and the supply current at it; "
                        "the sweeps go to DIR/<motor>/, then `characterize run` on DIR")
    g.add_argument("--readings", metavar="CSV", default=None,
                   help="the readings from a file (sweep,freq_hz,duty_pct,force_n,current_a) [asked at the prompt]")
    g.add_argument("--motor", default=None, help="the motor's name, its folder in DIR [x for axis 0, z for 1]")
    g.add_argument("--wheel-radius", type=_bounded(float, 1e-4, 10, "--wheel-radius"), default=None, metavar="M",
                   help="r of the rope bench's wheel, metres (required with --gauge)")
    g.add_argument("--theta", type=_bounded(float, 5.8, 174.2, "--theta"), default=90.0, metavar="DEG",
                   help="rope angle to the radius, degrees [90: a tangent]")
    g.add_argument("--supply-v", type=_bounded(float, 0.1, 1000, "--supply-v"), default=12.0, metavar="V",
                   help="the bridge's supply voltage [12]")
    g.add_argument("--freqs", metavar="HZ,HZ", default=None, help="the frequency sweep's carriers [50-500 by 25]")
    g.add_argument("--settle", type=_bounded(float, 0.05, 9, "--settle"), default=0.5, metavar="S",
                   help="seconds each setting is held before the reading [0.5]")
    g.add_argument("--config", metavar="FILE", default=None,
                   help="when the method passes, write the configuration here (as `characterize run DIR --out`)")
    return cs


def cmd_characterize(ctx: Ctx) -> int:
    """``torqueloop characterize ...``: the characterisation method's own command
    (torqueloop/characterize/command.py; docs/characterization.md), which a
    host-only install runs too (``sim`` is the study's: torqueloop-study)."""
    from torqueloop.characterize import command

    rest = list(ctx.args.rest)
    if rest[:1] == ["sweep"]:
        for k, v in vars(_sweep_parser().parse_args(rest[1:])).items():
            setattr(ctx.args, k, v)
        return cmd_char_sweep(ctx)
    try:
        return command.main(rest)
    except ImportError as e:   # `characterize sim` in a host-only install
        raise SimStackMissing(f"characterize {rest[0] if rest else ''}: needs the simulation stack "
                              f"({e.name} is missing): pip install 'torqueloop[sim]'") from None


def cmd_identify(ctx: Ctx) -> int:
    """``torqueloop identify``: the axis's plant from its encoder alone, with the
    open-loop drive (torqueloop/host/identify.py; docs/identification.md); a
    plant file with the estimates and physical parameters consistent with
    them (the rest of the plant from ``--base``)."""
    from sim_models.params import PlantParamError
    from sim_models.plantfile import export_text, plant_from_identified
    from sim_models.variants import plant_of
    from torqueloop.host import identify as ident

    a = ctx.args
    if a.resistance_ohm is not None and not (math.isfinite(a.resistance_ohm) and a.resistance_ohm > 0):
        raise BadValue(f"--resistance-ohm {a.resistance_ohm:g}: the winding's resistance, a positive number of ohm")
    try:
        base = plant_of(a.base).params()
    except PlantParamError as e:
        raise BadValue(f"--base: {e}") from None
    ctx.require_key("DRIVE")
    c = ctx.client
    mech = ctx.mech(a.axis)
    window = units.parse_position(a.travel, mech, "counts")
    if window <= 0:
        raise BadValue(f"--travel {a.travel}: give the travel allowed on either side, e.g. 10mm")
    r_loop = None if a.resistance_ohm is None else a.resistance_ohm + 2 * base.bridge.r_on_ohm
    plan = ident.Plan(axis=a.axis, window_counts=window, supply_v=base.bridge.supply_V, resistance_ohm=r_loop,
                      carrier_hz=a.pwm_freq)
    say = (lambda m: None) if a.json else (lambda m: print(m, file=sys.stderr, flush=True))
    res = ident.identify_axis(c, plan, say)
    name = P.SYSTEM.axes[a.axis].name
    est = res.estimates
    out = {"axis": a.axis, "seconds": round(res.seconds, 2), "estimates": est, "out": a.out}
    if a.out:
        plant = base
        if a.resistance_ohm is not None:
            plant = plant_from_identified(base, a.axis, est, a.resistance_ohm, a.pwm_freq)
        Path(a.out).write_text(export_text(plant, f"identified on axis {name}", "torqueloop identify",
                                           a.pwm_freq, measured={name: est}))
    ctx.out(out, lambda: "\n".join([f"axis {a.axis} ({name}) identified in {res.seconds:.1f} s:"]
                                     + [f"  {k} = {v:.6g}" for k, v in est.items() if not k.endswith("_sigma")]
                                     + ([f"wrote {a.out}"] if a.out else [])))
    return 0


def cmd_tune(ctx: Ctx) -> int:
    """``torqueloop tune``: gains from an identified plant file
    (torqueloop/host/tune.py, tunedesign.py; docs/identification.md), the
    predicted step and margins; ``--verify model|rtl`` runs them in the
    closed loop on the plant (torqueloop/sim/tuneverify.py); ``--apply``
    writes them to the board (``--save`` stores them)."""
    from sim_models.identifiable import identifiable_plant
    from sim_models.params import PlantParamError
    from sim_models.plantfile import identified, load_plant_file
    from sim_models.variants import PlantSpec
    from torqueloop.host import tune as htune
    from torqueloop.host.tunedesign import Wish

    a = ctx.args
    if a.save and not a.apply:
        raise BadValue("--save stores what --apply writes: give both")
    if a.verify_move != "step" and not a.verify:
        raise BadValue("--verify-move is the move --verify runs: give --verify model or rtl")
    if a.bandwidth is not None and a.settling is not None:
        raise BadValue("give --settling or --bandwidth, not both")
    def read(path: str, how: Callable[[str], Any]) -> Any:
        try:
            return how(path)
        except PlantParamError as e:
            raise BadValue(str(e)) from None
        except (OSError, ValueError) as e:     # unreadable, or not TOML
            raise BadValue(f"{path}: {e}") from None

    plant = read(a.plant_file, load_plant_file)
    ident = read(a.plant_file, identified)
    verify_spec = read(a.verify_plant or a.plant_file, PlantSpec.from_file)
    zeta_settle = 4.6                      # settling (2 %) = 4.6 / (zeta wn): the design's own rule
    settling = a.settling if a.settling is not None else (
        zeta_settle / (2 * math.pi * a.bandwidth) if a.bandwidth is not None else 0.5)
    wish = Wish(settling_s=settling, overshoot_pct=a.overshoot, tolerance_counts=a.tolerance, law=a.law,
                period_s=a.period_us * 1e-6)
    computed = None
    tunes = []
    for ax in _axes(a):
        name = P.SYSTEM.axes[ax].name
        d = ident.get(name)
        where = f"{a.plant_file} [identifiable.{name}]"
        if d is None:        # no measured section for this axis: what its physical parameters give
            computed = computed or identifiable_plant(plant, a.pwm_freq)
            d, where = computed[name].as_dict(), f"{a.plant_file} (axis {name} from its physical parameters)"
        t = htune.tune_axis(ax, d, wish, a.pwm_freq, where, plant.bridge.supply_V,
                            predict_s=a.verify_s if a.verify else 3.0)   # the same record as the verification's
        miss = htune.check_margins(t, a.min_gm, a.min_pm)
        if miss:
            raise htune.TuneError(miss)
        tunes.append(t)
    out: dict[str, Any] = {"plant_file": a.plant_file, "wish": {"settling_s": settling, "overshoot_pct": a.overshoot,
                                                               "tolerance_counts": a.tolerance, "law": a.law,
                                                               "period_us": a.period_us},
                           "axes": {t.name: t.as_dict() for t in tunes}}
    lines = []
    for t in tunes:
        dz, p, dz_pct = t.design, t.predicted, t.model.breakaway_pct
        lines += [f"axis {t.axis} ({t.name}): {dz.law.upper()} at {a.period_us} us, carrier {t.carrier_hz:.0f} Hz",
                  f"  kp {dz.kp:.4g} steps/count   kd {dz.kd:.4g} steps/(count/s)   ki {dz.ki:.4g} steps/(count s)",
                  f"  PW0 {dz.pw0} ticks ({100 * dz.pw0 / P.SYSTEM.pwm_full:.2f} %)   wn {dz.wn:.1f} rad/s   "
                  f"zeta {dz.zeta:.2f}",
                  f"  margins: gain {dz.gain_margin_db:.1f} dB, phase {dz.phase_margin_deg:.0f} deg"
                  + (f"   integral pole {dz.alpha:g} wn" if dz.law == "pid" else ""),
                  f"  friction compensation: FC_POS {dz.fc[0]} FC_NEG {dz.fc[1]} steps (smallest duty "
                  + " / ".join(f"{100 * (dz.pw0 + f * (P.SYSTEM.pwm_full - dz.pw0) / P.SYSTEM.pwm_full) / P.SYSTEM.pwm_full:.2f}"
                               for f in dz.fc)
                  + f" % +/-, dead zone {dz_pct[0]:.2f} / {dz_pct[1]:.2f} %), hunting guard {dz.izone_counts:g} counts",
                  f"  feed-forward on trapezoid moves: KVFF {dz.kvff:.4g} steps/(count/s), KAFF {dz.kaff:.4g} "
                  f"steps/(count/s^2); half the command left to the feedback up to VMAX {t.trapezoid[0]} counts/s, "
                  f"AMAX {t.trapezoid[1]} counts/s^2 (predicted peak following error there "
                  f"{t.predicted_following[0]:.0f} counts, {t.predicted_following[1]:.0f} without)",
                  f"  predicted one-turn step ({t.step_counts} counts): overshoot {p.overshoot_pct:.2f} %, "
                  f"settling {analysis.fmt_s(p.settling_time_s)} (+-2 counts: {analysis.fmt_s(t.predicted_tight_s)}), "
                  f"error {p.steady_state_error:.1f} counts",
                  "  board: " + " ".join(f"{k}={v}" for k, v in t.settings().items())]
        lines += [f"  note: {n}" for n in dz.notes]
        missed = p.overshoot_pct > a.overshoot or p.settling_time_s is None or p.settling_time_s > settling
        out["axes"][t.name]["meets_wish"] = not missed
        if missed:
            lines.append(f"  note: the design model misses the wish ({a.overshoot:g} %, {settling:g} s): saturation "
                         "and friction are beyond the linear design; try another --settling, or --verify")
    if a.verify:
        try:
            from torqueloop.sim import tuneverify
        except ImportError as e:
            raise SimStackMissing(f"--verify needs the simulation stack ({e.name} is missing): "
                                  "pip install 'torqueloop[sim]'") from None
        if not a.json:
            print("\n".join(lines), flush=True)
            lines = []
            print(f"verifying on the {'RTL board image (Verilator)' if a.verify == 'rtl' else 'fast model'} "
                  f"with {verify_spec.label}, {a.verify_s:g} s ...", file=sys.stderr, flush=True)
        v = tuneverify.verify(tunes, verify_spec, a.verify, a.verify_s, a.table1_s,
                              log=lambda *m, **k: print(*m, file=sys.stderr, flush=True), move=a.verify_move)
        out["verify"] = {k: m | ({"table1": v.table1[k]} if k in v.table1 else {})
                         | ({"without_feedforward": v.without_ff[k]} if k in v.without_ff else {})
                         for k, m in v.tuned.items()} | {
            "path": v.path, "plant": v.plant, "seconds": v.seconds, "faults": v.faults, "wall_s": v.wall_s,
            "move": v.move}
        out["table1"] = v.table1
        lines.append(f"{'':24}{'predicted':>11}{'measured':>11}{'Table 1' if v.table1 else '':>11}   "
                     f"({v.path}, {v.plant})")
        for t in tunes:
            m = v.tuned[t.name]
            trap = v.move == "trapezoid" and t.predicted_trapezoid is not None
            p, p_tight = (t.predicted_trapezoid, t.predicted_trapezoid_tight_s) if trap else (t.predicted,
                                                                                             t.predicted_tight_s)
            r = v.table1.get(t.name, {k: "" for k in m})
            for label, pv, mv, rv, f in (
                    ("overshoot (%)", p.overshoot_pct, m["overshoot_pct"], r["overshoot_pct"], ".2f"),
                    ("settling 2 % (s)", p.settling_time_s, m["settling_time_s"], r["settling_time_s"], ".3f"),
                    ("settling 2 counts (s)", p_tight, m["settling_time_2_counts_s"],
                     r["settling_time_2_counts_s"],
                     ".3f"),
                    ("error (counts)", p.steady_state_error, m["steady_state_error_counts"],
                     r["steady_state_error_counts"], ".1f")):
                cells = ["-" if x is None else x if x == "" else format(x, f) for x in (pv, mv, rv)]
                lines.append(f"  {t.name} {label:<22}{cells[0]:>11}{cells[1]:>11}{cells[2]:>11}")
            if t.name in v.without_ff:
                pf, w = t.predicted_following, v.without_ff[t.name]["peak_following_error_counts"]
                lines.append(f"  {t.name} {'peak following (counts)':<22}{pf[0]:>11.0f}"
                             f"{m['peak_following_error_counts']:>11.0f}")
                lines.append(f"  {t.name} {'  without feed-forward':<22}{pf[1]:>11.0f}{w:>11.0f}   (fast model)")
        if v.faults and any(v.faults):
            lines.append(f"  faults during the run: {', '.join(describe_faults(f) for f in v.faults if f)}")
    if a.apply:
        ctx.require_key("SET_PARAM")
        c = ctx.client
        assert isinstance(c, Client) or hasattr(c, "set_param")
        out["applied"] = htune.apply(c, tunes, a.save)    # type: ignore[arg-type]
        lines.append(f"applied to the board (PERIOD_US {out['applied']['period_us']})"
                     + (", saved" if a.save else "; `torqueloop save` keeps it over a power cycle"))
    ctx.out(out, "\n".join(lines))
    if a.verify and out["verify"]["faults"] and any(out["verify"]["faults"]):
        return EXIT_REFUSED
    return 0


def cmd_plant(ctx: Ctx) -> int:
    """``torqueloop plant export``: a plant variant or plant file as a plant
    file, with what an encoder-only identification can see of each axis
    (sim_models/plantfile.py; docs/identification.md).  Needs no board."""
    from sim_models.params import PlantParamError
    from sim_models.plantfile import export_text
    from sim_models.variants import describe, plant_choice

    a = ctx.args
    try:
        plant = plant_choice(a.variant, a.plant_file)
    except PlantParamError as e:
        raise BadValue(str(e)) from None
    carrier = a.pwm_freq
    if not (math.isfinite(carrier) and 0 < carrier <= P.SYSTEM.bridge_max_hz):
        raise BadValue(f"--pwm-freq {carrier:g} Hz: give a carrier in (0, {P.SYSTEM.bridge_max_hz}] Hz")
    text = export_text(plant.params(), plant.label, "" if plant.file else describe(plant.name), carrier)
    if a.out:
        Path(a.out).write_text(text)
        print(f"wrote {a.out} (plant {plant.label}, identifiable dead zones at {carrier:g} Hz)", file=sys.stderr)
    else:
        sys.stdout.write(text)
    return 0


def cmd_shell(ctx: Ctx) -> int:
    from torqueloop.host.shell import Shell

    return Shell(ctx, main, parser()).run()


class SimStackMissing(Exception):
    """``torqueloop sim`` in an install without the simulation extras."""


# ---- argument parsing --------------------------------------------------------------

def _bounded(kind: type, lo: float, hi: float, what: str) -> Callable[[str], Any]:
    """An argparse type: a finite number of ``kind`` in [lo, hi]; anything else
    is a usage error (one line, exit status 2)."""
    def conv(text: str) -> Any:
        try:
            v = kind(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"{what}: {text!r} is not {'a number' if kind is float else 'an integer'}")
        if isinstance(v, float) and not math.isfinite(v):
            raise argparse.ArgumentTypeError(f"{what}: {text} is not a finite number")
        if not lo <= v <= hi:
            raise argparse.ArgumentTypeError(f"{what}: {text} is outside [{lo:g}, {hi:g}]")
        return v
    return conv


class _Parser(argparse.ArgumentParser):
    """A usage error is one line on stderr and exit status 2.  A negative
    number with a unit (``-1mm``, ``-90deg``) is an argument, not an option."""

    def __init__(self, *a: Any, **kw: Any) -> None:
        super().__init__(*a, **kw)
        self._negative_number_matcher = re.compile(r"^-(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?[a-z/^0-9]*$")

    def error(self, message: str) -> None:  # type: ignore[override]
        self.exit(2, f"{self.prog}: {message} (see {self.prog} -h)\n")


def parser() -> argparse.ArgumentParser:
    p = _Parser(prog="torqueloop", description=__doc__.split("\n\n")[0],
                                formatter_class=argparse.RawDescriptionHelpFormatter,
                                epilog="docs/host.md has the walk-through; docs/protocol.md the parameters.")
    p.add_argument("-u", "--url", default=os.environ.get("TORQUELOOP_URL", DEFAULT_URL),
                   help="/dev/ttyUSB0, socket://HOST:2000 (RN-XV or `torqueloop sim`) "
                        f"[$TORQUELOOP_URL or {DEFAULT_URL}]")
    p.add_argument("-b", "--baud", type=_bounded(int, 50, 20_000_000, "baud"), default=DEFAULT_BAUD,
                   help="serial baud rate [115200]")
    p.add_argument("--timeout", type=_bounded(float, 0.001, 3600, "timeout"), default=0.5,
                   help="seconds to wait for each reply [0.5]")
    p.add_argument("--retries", type=_bounded(int, 0, 100, "retries"), default=3, help="resends before giving up [3]")
    p.add_argument("-k", "--key-file", metavar="FILE", default=None,
                   help=f"the link key (docs/security.md); never the key itself [${auth.KEY_FILE_ENV}]")
    p.add_argument("--json", action="store_true", help="machine-readable output")
    p.add_argument("--server", metavar="ADDR", default=None,
                   help=f"go through the `torqueloop serve` at HOST:PORT [${hserve.SERVER_ENV}, or the one "
                        "serving --url found in its state file]")
    p.add_argument("--no-server", action="store_true", help="talk to the board directly even when a server runs")
    p.add_argument("--version", action="version", version=f"torqueloop {torqueloop.__version__}")
    sub = p.add_subparsers(dest="command", required=True, metavar="COMMAND")

    def axis_opts(sp: argparse.ArgumentParser, all_ok: bool = True) -> None:
        sp.add_argument("-a", "--axis", type=int, default=0, choices=range(P.AXIS_COUNT), help="axis [0]")
        if all_ok:
            sp.add_argument("--all", action="store_true", help="both axes")

    def unit_opt(sp: argparse.ArgumentParser, default: str | None = "rad") -> None:
        if default is None:      # a command that takes a position: bare numbers are counts unless --unit
            sp.add_argument("--unit", default=None, choices=units.POSITION_UNITS,
                            help="unit of bare numbers and of the output [bare numbers: counts]")
        else:
            sp.add_argument("--unit", default=default, choices=units.POSITION_UNITS,
                            help=f"position unit of the output [{default}]")

    sp = sub.add_parser("info", help="firmware identity, build id and link counters")
    sp.set_defaults(fn=cmd_info)
    sp = sub.add_parser("status", help="state, position and decoded faults of an axis")
    axis_opts(sp)
    unit_opt(sp)
    sp.set_defaults(fn=cmd_status)
    sp = sub.add_parser("get", help="read parameters (no name: all of them)")
    sp.add_argument("names", nargs="*", help="kp, kd, ki, law, pwm_freq, pw0, period ... or protocol names")
    axis_opts(sp, False)
    sp.set_defaults(fn=cmd_get)
    sp = sub.add_parser("set", help="write one parameter in physical units (kp 0.82, pwm_freq 450, law pid, "
                                    "soft_max 40mm, vmax 5mm/s)")
    sp.add_argument("name", help="kp, kd, ki, law, pwm_freq, period, soft_min, soft_max, vmax, amax, home_vel, "
                                 "... (`get` lists them) or a protocol name")
    sp.add_argument("value", help="positions and limits in mm, rev, rad, deg or counts (a bare number), "
                                  "speeds per second (5mm/s), pwm_freq in Hz")
    sp.add_argument("--nearest", action="store_true",
                    help=f"pwm_freq: store the nearest carrier the divider makes even when it is more than "
                         f"{units.PWM_FREQ_TOL:.0%} from the request")
    axis_opts(sp, False)
    sp.set_defaults(fn=cmd_set)
    for name, on in (("enable", True), ("disable", False)):
        sp = sub.add_parser(name, help=f"{name} the drive of an axis")
        axis_opts(sp)
        sp.set_defaults(fn=lambda ctx, on=on: cmd_enable(ctx, on))
    sp = sub.add_parser("move", help="new target: 6.28rad, 4mm, -1mm, 1rev, 90deg or counts (a bare number)")
    sp.add_argument("target")
    axis_opts(sp, False)
    unit_opt(sp, None)
    sp.add_argument("--trapezoid", action="store_true", help="trapezoidal profile (VMAX, AMAX) instead of a step")
    sp.add_argument("--relative", action="store_true", help="target is relative to the present position")
    sp.add_argument("--enable", action="store_true", help="enable the axis first (after the move is checked)")
    sp.add_argument("--unhomed", action="store_true",
                    help="move although the axis is not homed (positions relative to power-up)")
    sp.add_argument("--wait", type=_bounded(float, 0, 86400, "--wait"), default=0.0, metavar="S",
                    help="wait up to S seconds for the axis to settle, keeping the link alive; prints "
                         "settled or not settled (exit 1), then disables the axis unless --hold")
    sp.add_argument("--hold", action="store_true",
                    help="afterwards keep the axis enabled, sending heartbeats, until Ctrl-C (then disable)")
    sp.add_argument("--tolerance", type=_bounded(int, 0, 2**31 - 1, "--tolerance"), default=20,
                    help="settled: within this many counts of the target for 0.3 s [20]")
    sp.set_defaults(fn=cmd_move)
    sp = sub.add_parser("home", help="home an axis: to its negative or positive limit switch, or here")
    sp.add_argument("mode", nargs="?", default="neg", choices=list(P.HOME_MODES),
                    help="neg / pos: seek that limit switch (axis enabled); here: the present position [neg]")
    sp.add_argument("--index", action="store_true", help="after the switch, go on to the next encoder index pulse")
    sp.add_argument("--wait", type=_bounded(float, 0, 86400, "--wait"), default=60.0, metavar="S",
                    help="wait up to S seconds for homing to finish, keeping the link alive [60]")
    sp.add_argument("--enable", action="store_true", help="accepted for scripts; homing to a switch enables its axis itself (every axis disabled first) and disables it at the end")
    sp.add_argument("--hold", action="store_true",
                    help="afterwards keep the axis enabled, sending heartbeats, until Ctrl-C (then disable)")
    axis_opts(sp, False)
    sp.set_defaults(fn=cmd_home)
    sp = sub.add_parser("drive", help="open-loop drive at a fixed duty (5%%, -5%%): enables the axis, prints "
                                      "the encoder count and speed (the sign check), disables it at the end")
    sp.add_argument("duty", help="signed duty in percent of the full command, e.g. 5%% or -5%% (at most CMD_LIMIT)")
    axis_opts(sp, False)
    sp.add_argument("--pwm-freq", type=_bounded(float, 1, 1e7, "--pwm-freq"), default=None, metavar="HZ",
                    help="PWM carrier for this drive (the nearest the divider makes; restored afterwards)")
    sp.add_argument("--for", dest="seconds", type=_bounded(float, 0.1, 3600, "--for"), default=2.0, metavar="S",
                    help="seconds to drive [2]")
    sp._negative_number_matcher = re.compile(r"^-\d*\.?\d+%?$")   # `drive -5%`: a duty, not an option
    sp.set_defaults(fn=cmd_drive)
    sp = sub.add_parser("save", help="store the running parameters on the board (its configuration flash): "
                                     "it starts with them after a power cycle, reset or upload")
    sp.set_defaults(fn=cmd_save)
    sp = sub.add_parser("stop", help="hold the present position")
    axis_opts(sp)
    sp.set_defaults(fn=cmd_stop)
    sp = sub.add_parser("clear-fault", help="clear latched faults whose cause is gone")
    axis_opts(sp)
    sp.set_defaults(fn=cmd_clear_fault)
    sp = sub.add_parser("monitor", help="live terminal view of the telemetry")
    axis_opts(sp, False)
    unit_opt(sp)
    sp.add_argument("--duration", type=_bounded(float, 0, 1e7, "--duration"), default=0.0,
                    help="seconds (0 = until Ctrl-C)")
    sp.add_argument("--every", type=_bounded(int, 1, 65535, "--every"), default=4,
                    help="one record every N control periods [4]")
    sp.set_defaults(fn=cmd_monitor)
    sp = sub.add_parser("plot", help="live plot; --save PREFIX writes PREFIX.png and PREFIX.csv")
    axis_opts(sp)
    unit_opt(sp)
    sp.add_argument("--duration", type=_bounded(float, 0, 1e7, "--duration"), default=0.0,
                    help="seconds (0 = until Ctrl-C; needed with --save)")
    sp.add_argument("--every", type=_bounded(int, 1, 65535, "--every"), default=1,
                    help="one record every N control periods [1]")
    sp.add_argument("--save", metavar="PREFIX")
    sp.set_defaults(fn=cmd_plot)
    sp = sub.add_parser("step-test", help="step, capture, plot + CSV + overshoot/settling/RMSE")
    sp.add_argument("target", help="6.28rad, 4mm, 1rev, 90deg or counts (a bare number)")
    axis_opts(sp, False)
    unit_opt(sp, None)
    sp.add_argument("--relative", action="store_true", help="step relative to the present position")
    sp.add_argument("--trapezoid", action="store_true")
    sp.add_argument("--unhomed", action="store_true",
                    help="step although the axis is not homed (positions relative to power-up)")
    sp.add_argument("--duration", type=_bounded(float, 0.01, 1e5, "--duration"), default=2.0,
                    help="board seconds captured after the step [2]")
    sp.add_argument("--pre", type=_bounded(float, 0, 1e3, "--pre"), default=0.1,
                    help="board seconds captured before the step [0.1]")
    sp.add_argument("--band", type=_bounded(float, 0.001, 100, "--band"), default=2.0,
                    help="settling band, %% of the step [2]")
    sp.add_argument("--out", default="build/step", help="output folder [build/step]")
    sp.add_argument("--keep-enabled", action="store_true", help="leave the axis enabled afterwards")
    sp.set_defaults(fn=cmd_step_test)
    sp = sub.add_parser("config", help="save or load all parameters (JSON); load also takes "
                                       "the characterisation file")
    sp.add_argument("action", choices=["save", "load"])
    sp.add_argument("file")
    sp.add_argument("--force", action="store_true", help="load even if saved from another build id")
    sp.set_defaults(fn=cmd_config)
    sp = sub.add_parser("upload", help="load firmware through the boot ROM bootloader, then check it answers")
    sp.add_argument("file", help="FIRMWARE.elf (RAM-linked RV32), or with --raw a flat .bin")
    sp.add_argument("--raw", action="store_true",
                    help="the file is a flat RAM image (it must carry the firmware image header)")
    sp.add_argument("--window", type=_bounded(float, 0.1, 3600, "--window"), default=5.0,
                    help="seconds to wait for the bootloader [5]")
    sp.set_defaults(fn=cmd_upload)
    sp = sub.add_parser("key", help="key files: `key new FILE` writes a fresh key, `key id [FILE]` names one")
    sp.add_argument("action", choices=["new", "id"])
    sp.add_argument("file", nargs="?")
    sp.set_defaults(fn=cmd_key)
    sp = sub.add_parser("identify", help="the axis's plant from its encoder, with the open-loop drive "
                                         "(docs/identification.md)")
    axis_opts(sp, False)
    sp.add_argument("--travel", required=True, metavar="DIST",
                    help="travel allowed on either side of where the axis stands (10mm, 2rev, 5000)")
    sp.add_argument("--resistance-ohm", type=float, default=None, metavar="OHM",
                    help="the winding's resistance, measured with a meter at the motor's terminals: "
                         "without it only the voltage-domain quantities are identified")
    sp.add_argument("--pwm-freq", type=_bounded(float, 1, 25_000, "--pwm-freq"), default=float(P.SYSTEM.working_hz),
                    metavar="HZ", help=f"the carrier to identify at [{P.SYSTEM.working_hz}]")
    sp.add_argument("--base", default="paper", help="the plant the rest comes from (springs, screw, table) [paper]")
    sp.add_argument("--out", default=None, metavar="FILE", help="write a plant file")
    sp.set_defaults(fn=cmd_identify)
    sp = sub.add_parser("tune", help="gains from an identified plant file, the predicted step and margins; "
                                     "--verify model|rtl, --apply [--save] (docs/identification.md)")
    axis_opts(sp)
    sp.add_argument("--plant-file", required=True, metavar="FILE",
                    help="the plant file (`torqueloop identify --out`, `torqueloop plant export`)")
    sp.add_argument("--law", type=str.lower, choices=["pd", "pid"], default="pid", help="control law [pid]")
    sp.add_argument("--settling", type=_bounded(float, 0.01, 100, "--settling"), default=None, metavar="S",
                    help="settling time wished for (2 %% band), seconds [0.5]")
    sp.add_argument("--bandwidth", type=_bounded(float, 0.01, 1000, "--bandwidth"), default=None, metavar="HZ",
                    help="loop bandwidth instead of --settling, Hz")
    sp.add_argument("--overshoot", type=_bounded(float, 0, 50, "--overshoot"), default=2.0, metavar="PCT",
                    help="overshoot limit, percent [2]")
    sp.add_argument("--tolerance", type=_bounded(float, 0.5, 10_000, "--tolerance"), default=2.0, metavar="COUNTS",
                    help="how far from the target a PD may stick, counts [2]")
    sp.add_argument("--period-us", type=_bounded(int, 50, 25_000, "--period-us"), default=1000, metavar="US",
                    help="control period the gains are for (PERIOD_US), microseconds [1000]")
    sp.add_argument("--pwm-freq", type=_bounded(float, 100, P.SYSTEM.bridge_max_hz, "--pwm-freq"),
                    default=float(P.SYSTEM.working_hz), metavar="HZ",
                    help=f"carrier: the lowest the divider makes at or above HZ [{P.SYSTEM.working_hz}: 24.4 kHz]")
    sp.add_argument("--min-gm", type=_bounded(float, 0, 60, "--min-gm"), default=6.0, metavar="DB",
                    help="gain margin the design must keep, dB [6]")
    sp.add_argument("--min-pm", type=_bounded(float, 0, 90, "--min-pm"), default=30.0, metavar="DEG",
                    help="phase margin the design must keep, degrees [30]")
    sp.add_argument("--verify", choices=["model", "rtl"], default=None,
                    help="run the tuned one-turn step in the closed loop: on the fast model or the RTL board image")
    sp.add_argument("--verify-move", choices=["step", "trapezoid"], default="step",
                    help="the verification's one-turn move: the paper's step, or a trapezoid (at the VMAX, AMAX "
                         "printed) with the feed-forward and, on the fast model, without it [step]")
    sp.add_argument("--verify-plant", default=None, metavar="FILE",
                    help="the plant file to verify on [the --plant-file]")
    sp.add_argument("--verify-s", type=_bounded(float, 0.1, 60, "--verify-s"), default=3.0, metavar="S",
                    help="simulated seconds of the verification (z of the scaled lab plant settles into +-2 counts "
                         "at 2.4 s) [3]")
    sp.add_argument("--table1-s", type=_bounded(float, 0, 60, "--table1-s"), default=0.0, metavar="S",
                    help="with --verify: also run the Table 1 gains of the same law on the same plant for S "
                         "simulated seconds (fast path, the paper's period and carriers; slow) [0: no]")
    sp.add_argument("--apply", action="store_true", help="write the settings to the connected board")
    sp.add_argument("--save", action="store_true", help="with --apply: store them on the board")
    sp.set_defaults(fn=cmd_tune)
    sp = sub.add_parser("plant", help="plant files: `plant export VARIANT > my.toml` (docs/identification.md)")
    sp.add_argument("action", choices=["export"])
    sp.add_argument("variant", nargs="?", default=None, help="plant variant: paper-printed, paper, lab, ... [paper]")
    sp.add_argument("--plant-file", default=None, metavar="FILE", help="re-export a plant file (fresh identifiable part)")
    sp.add_argument("--pwm-freq", type=float, default=float(P.SYSTEM.working_hz), metavar="HZ",
                    help=f"the carrier the identifiable dead zones are given at [{P.SYSTEM.working_hz}]")
    sp.add_argument("--out", default=None, metavar="FILE", help="write here instead of to stdout")
    sp.set_defaults(fn=cmd_plant)
    sp = sub.add_parser("sim", help="run the simulated board on a local TCP port (with the --key-file key)")
    sp.add_argument("--host", default="127.0.0.1")
    sp.add_argument("--port", type=_bounded(int, 0, 65535, "--port"), default=2000,
                    help="TCP port (0 = any free one) [2000]")
    sp.add_argument("--speed", type=_bounded(float, 0, 1e6, "--speed"), default=1.0,
                    help="simulated seconds per wall second [1]")
    sp.add_argument("--hello", action="store_true", help="send *HELLO* on connect, like an RN-XV")
    sp.add_argument("--build-id", type=_bounded(lambda t: int(t, 0), 0, 0xFFFF_FFFF, "--build-id"),
                    default=0x51B0_0001, help="build id the board reports [0x51b00001]")
    sp.add_argument("--seed", type=_bounded(int, 0, 2**32 - 1, "--seed"), default=0, help="plant random seed")
    sp.add_argument("--plant", default=None,
                    help="plant variant: paper-printed, paper or lab (lab-no-EFFECT switches one off) [paper]")
    sp.add_argument("--plant-file", default=None, metavar="FILE",
                    help="a plant file instead of a variant (`torqueloop plant export`, `torqueloop identify`)")
    sp.add_argument("--switches", type=_bounded(int, 100, 2**30, "--switches"), default=None, metavar="COUNTS",
                    help="the simulated stage's limit switches open beyond +-COUNTS from the power-up position "
                         "[400000, about +-190 mm: homing at the default HOME_VEL takes minutes]")
    sp.add_argument("--rtl", action="store_true",
                    help="serve the RTL co-simulation (torqueloop/cosim) instead of the firmware-in-the-loop board")
    sp.add_argument("--flash", metavar="FILE", default=None,
                    help="keep the board's configuration flash (its saved parameters) in FILE, so a new `sim` "
                         "on the same FILE is the board after a power cycle [in memory]")
    sp.set_defaults(fn=cmd_sim)
    sp = sub.add_parser("serve", help="hold the board's link and session for several clients at once "
                                      "(monitor in one terminal, move in another)")
    sp.add_argument("--host", default="127.0.0.1", help="address to listen on [127.0.0.1: this machine only]")
    sp.add_argument("--port", type=_bounded(int, 0, 65535, "--port"), default=hserve.DEFAULT_PORT,
                    help=f"TCP port (0 = any free one) [{hserve.DEFAULT_PORT}]")
    sp.add_argument("--quiet", action="store_true", help="do not log clients coming and going")
    sp.add_argument("--http", nargs="?", const="127.0.0.1:7131", default=None, metavar="ADDR:PORT",
                    help="also serve the browser dashboard there [127.0.0.1:7131]; on any other address "
                         "every page needs a token, printed at start (docs/host.md, Dashboard)")
    sp.add_argument("--http-tokens", metavar="FILE", default=None,
                    help="the dashboard's tokens from FILE (lines `command TOKEN`, `watch TOKEN`; mode 600) "
                         "instead of fresh ones at each start")
    sp.set_defaults(fn=cmd_serve)
    sp = sub.add_parser("characterize", add_help=False,
                        help="the paper's characterisation method on your sweeps: run, step5, check, show, "
                             "export (and sim, with the simulation stack); `characterize sweep`: the board as "
                             "the PWM source; `characterize -h`")
    sp.add_argument("rest", nargs=argparse.REMAINDER)
    sp.set_defaults(fn=cmd_characterize)
    sp = sub.add_parser("shell", help="interactive session: the commands above, history, completion, "
                                      "a live text plot while moves run")
    sp.add_argument("--plot-file", metavar="FILE", help="also append every live-plot frame to FILE")
    sp.add_argument("--script", metavar="FILE", help="read the commands from FILE instead of the terminal")
    sp.set_defaults(fn=cmd_shell)
    return p


#: exit status (module docstring)
EXIT_REFUSED, EXIT_BAD_INPUT, EXIT_NO_ANSWER = 1, 2, 3
EXIT_INTERRUPTED = 130       # what a shell reports for a command ended by SIGINT
#: a value the board refuses as such is bad input, whoever checked it (the tool before sending, or the board)
BAD_INPUT_STATUSES = frozenset({P.STATUS["BAD_ARG"], P.STATUS["RANGE"]})


def _terminated(signum: int, frame: Any) -> None:
    """SIGTERM (`kill`, a service manager) ends a command the way Ctrl-C does."""
    raise KeyboardInterrupt


def _stdout_closed() -> bool:
    """True if stdout's reader has gone (a pipe with no reader polls as an
    error); stdout then points at /dev/null, so the interpreter's last flush
    does not report the broken pipe again."""
    import select

    try:
        fd = sys.stdout.fileno()
        p = select.poll()
        p.register(fd, select.POLLOUT)
        gone = any(ev & (select.POLLERR | select.POLLHUP) for _, ev in p.poll(0))
    except (OSError, ValueError, AttributeError):
        return False
    if gone:
        os.dup2(os.open(os.devnull, os.O_WRONLY), fd)
    return gone


def main(argv: list[str] | None = None, *, client: Client | RemoteClient | None = None,
         tick: Callable[[], None] | None = None) -> int:
    """Run one command.  ``client``: an open session to run it on (the shell's;
    left open); ``tick``: called while a move or homing is waited for (the
    shell's live plot)."""
    ap = parser()
    args, extra = ap.parse_known_args(argv)      # a usage error exits 2 with one line
    if extra and args.command != "characterize":
        ap.error(f"unrecognized arguments: {' '.join(extra)}")
    if args.command == "characterize":           # its options are its own: `characterize -h`
        args.rest = extra + list(args.rest)
    ctx = Ctx(args)
    if client is not None:
        ctx._client, ctx.shared = client, True
    ctx.tick = tick or (lambda: None)
    own_term = not ctx.shared and threading.current_thread() is threading.main_thread()
    prev_term = signal.signal(signal.SIGTERM, _terminated) if own_term else None
    try:
        return args.fn(ctx)
    except KeyboardInterrupt:
        if ctx.shared:
            raise                 # the shell's own Ctrl-C handling (torqueloop/host/shell.py)
        print(f"torqueloop: interrupted; {ctx.interrupted()}", file=sys.stderr)
        return EXIT_INTERRUPTED
    except BrokenPipeError as e:
        if not _stdout_closed():
            print(f"torqueloop: {e}", file=sys.stderr)
            return EXIT_REFUSED
        return 0      # the reader stopped early (`info | head -1`): what it read was printed
    except (NoAnswer, LinkOpenError, LinkClosed) as e:
        print(f"torqueloop: {e}", file=sys.stderr)
        return EXIT_NO_ANSWER
    except CommandRejected as e:
        hint = REFUSAL_HINT.get(e.rule)
        print(f"torqueloop: {e}" + (f"; {hint}" if hint else ""), file=sys.stderr)
        return EXIT_BAD_INPUT if e.status in BAD_INPUT_STATUSES else EXIT_REFUSED
    except (BadValue, hconfig.HostConfigError, ImageRefused) as e:
        print(f"torqueloop: {e}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except (ProtocolError, SimStackMissing, ValueError, OSError) as e:
        print(f"torqueloop: {e}", file=sys.stderr)
        return EXIT_REFUSED
    finally:
        if own_term:
            signal.signal(signal.SIGTERM, prev_term)
        try:
            ctx.close()
        except OSError:
            pass


if __name__ == "__main__":
    sys.exit(main())
