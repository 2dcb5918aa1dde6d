# SPDX-License-Identifier: MIT
"""Physical units on the command line, integers on the wire.

Positions: ``6.28rad``, ``4mm``, ``1rev``, ``8400`` or ``8400counts``; the
board's COUNTS_PER_REV and PITCH_UM (read from it) convert them, so the tool
needs no second copy of the mechanics.

Parameters: a friendly name in SI units (``kp`` in N m/rad, ``pwm_freq`` in
Hz, ``period`` in s ...) maps to one protocol parameter and a scale; every
raw protocol name (``KP_Q16``, ``FOLLOW_LIMIT``) is accepted as well.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass

from torqueloop.spec import protocol as P
from torqueloop.spec.pwm import carrier_hz, divider_for
from torqueloop.spec.system import SYSTEM

CLK_HZ = SYSTEM.clk_hz   # the board reports its own in IDENTIFY
LAWS = {"off": 0, "p": 1, "pd": 2, "pid": 3}
INT32_MIN, INT32_MAX = -(1 << 31), (1 << 31) - 1


class BadValue(ValueError):
    """A value refused before anything is sent (not a number, not finite, out
    of range, too large for the wire); ``str()`` is one line for a person."""


def number(text: str, what: str) -> float:
    """A finite number from the command line, or BadValue."""
    try:
        v = float(text)
    except (TypeError, ValueError):
        raise BadValue(f"{what}: {text!r} is not a number") from None
    if not math.isfinite(v):
        raise BadValue(f"{what}: {text} is not a finite number")
    return v


@dataclass(frozen=True)
class Mechanics:
    counts_per_rev: int = SYSTEM.counts_per_turn
    pitch_um: int = SYSTEM.lead_um

    def to_counts(self, value: float, unit: str) -> int:
        if not math.isfinite(value):
            raise BadValue(f"position {value} is not a finite number")
        if unit in ("", "counts", "count", "cts"):
            c = value
        elif unit == "rad":
            c = value * self.counts_per_rev / (2 * math.pi)
        elif unit in ("rev", "turn", "turns"):
            c = value * self.counts_per_rev
        elif unit == "mm":
            c = value * 1000 * self.counts_per_rev / self.pitch_um
        elif unit == "deg":
            c = value * self.counts_per_rev / 360
        else:
            raise BadValue(f"unknown position unit {unit!r} (use rad, mm, rev, deg or counts)")
        if not INT32_MIN <= c <= INT32_MAX:
            raise BadValue(f"position {value:g} {unit or 'counts'} is {c:.4g} counts, beyond the encoder's "
                           f"32-bit range [{INT32_MIN}, {INT32_MAX}]")
        return int(round(c))

    def from_counts(self, counts: float, unit: str) -> float:
        if unit in ("", "counts"):
            return float(counts)
        if unit == "rad":
            return counts * 2 * math.pi / self.counts_per_rev
        if unit == "mm":
            return counts * self.pitch_um / 1000 / self.counts_per_rev
        if unit == "rev":
            return counts / self.counts_per_rev
        if unit == "deg":
            return counts * 360 / self.counts_per_rev
        raise ValueError(f"unknown position unit {unit!r}")


_POS_RE = re.compile(r"^\s*([-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?)\s*([a-z]*)\s*$")


def parse_position(text: str, mech: Mechanics, default_unit: str = "counts") -> int:
    """``'6.28rad'`` -> counts.  A bare number is in ``default_unit``."""
    m = _POS_RE.match(text.lower())
    if not m:
        raise BadValue(f"cannot read position {text!r} (examples: 6.28rad, 4mm, 1rev, 8400)")
    return mech.to_counts(float(m.group(1)), m.group(2) or default_unit)


@dataclass(frozen=True)
class Friendly:
    """A parameter as people say it: ``value_SI * scale = raw``."""

    param: str
    scale: float
    unit: str
    help: str


FRIENDLY: dict[str, Friendly] = {
    "kp": Friendly("KP_UNM_RAD", 1e6, "N m/rad", "proportional gain, eq. (20)"),
    "kd": Friendly("KD_UNMS_RAD", 1e6, "N m s/rad", "derivative gain, eq. (21)"),
    "ki": Friendly("KI_UNM_RADS", 1e6, "N m/(rad s)", "integral gain, eq. (22)"),
    "tau_max": Friendly("TAU_MAX_MNM", 1e3, "N m", "torque at full command (the paper's tau_max)"),
    "period": Friendly("PERIOD_US", 1e6, "s", "control period (the paper's 25 ms)"),
    "link_timeout": Friendly("LINK_TIMEOUT_MS", 1e3, "s", "link watchdog of an enabled axis"),
    "pw0": Friendly("PW0", 1, "ticks of 1023", "dead-zone edge PW0, eq. (1)"),
    "pwmax": Friendly("PWMAX", 1, "ticks of 1023", "duty at full command PW_F, eq. (1)"),
    "cmd_limit": Friendly("CMD_LIMIT", 1, "steps", "PWM command saturation, eq. (19)"),
    "follow_limit": Friendly("FOLLOW_LIMIT", 1, "counts", "following-error fault limit"),
    "soft_min": Friendly("SOFT_MIN", 1, "counts", "lowest allowed position"),
    "soft_max": Friendly("SOFT_MAX", 1, "counts", "highest allowed position"),
    "vmax": Friendly("VMAX", 1, "counts/s", "trapezoid top speed"),
    "amax": Friendly("AMAX", 1, "counts/s^2", "trapezoid acceleration"),
    "counts_per_rev": Friendly("COUNTS_PER_REV", 1, "counts", "encoder counts per screw turn"),
    "pitch": Friendly("PITCH_UM", 1e6, "m", "ball-screw lead"),
    "stall_cmd": Friendly("STALL_CMD", 1, "steps", "runaway check: command that must move the axis"),
    "stall_time": Friendly("STALL_MS", 1e3, "s", "runaway check: time it has to move it"),
    "limit_sw": Friendly("LIMIT_SW", 1, "", "1 = limit switches wired, 0 = none"),
    "home_vel": Friendly("HOME_VEL", 1, "counts/s", "homing speed"),
    "home_pos": Friendly("HOME_POS", 1, "counts", "position given to the home point"),
    "pwm_max": Friendly("PWM_MAX_HZ", 1, "Hz", "PWM carrier ceiling (the bridge's rating)"),
}
# Parameters with their own conversions (not a plain scale).
SPECIAL = {"law": "LAW", "pwm_freq": "FDIV"}


def resolve(name: str) -> tuple[str, str]:
    """User name -> (protocol parameter, kind): kind 'friendly', 'special' or 'raw'.
    A protocol name spelt as in docs/protocol.md (upper case) is always raw."""
    if name in P.PARAMS:
        return name, "raw"
    low = name.lower()
    if low in FRIENDLY:
        return FRIENDLY[low].param, "friendly"
    if low in SPECIAL:
        return SPECIAL[low], "special"
    up = name.upper()
    if up in P.PARAMS:
        return up, "raw"
    known = ", ".join(sorted([*FRIENDLY, *SPECIAL]))
    raise BadValue(f"unknown parameter {name!r}; friendly names: {known}; or a protocol name "
                   f"such as KP_Q16 (docs/protocol.md)")


def to_raw(name: str, text: str, clk_hz: int = CLK_HZ) -> tuple[str, int]:
    """(protocol parameter, raw integer) for ``set NAME VALUE``; BadValue for
    anything the parameter cannot hold (the message gives its range in the
    unit the value was given in)."""
    param, kind = resolve(name)
    p = P.PARAMS[param]
    if kind == "special":
        if param == "LAW":
            if text.lower() in LAWS:
                return param, LAWS[text.lower()]
            v = number(text, name)
            if v not in range(p.min, p.max + 1):
                raise BadValue(f"law {text!r}: use {', '.join(LAWS)} or 0..3")
            return param, int(v)
        f = number(text, name)
        if f <= 0:
            raise BadValue(f"pwm_freq {text} Hz: the carrier must be above 0 Hz")
        return param, divider_for(f, clk_hz)
    if kind == "friendly":
        fr = FRIENDLY[name.lower()]
        raw = number(text, name) * fr.scale
        if not p.min <= round(raw) <= p.max:
            raise BadValue(f"{name} {text} {fr.unit}".rstrip() + f" is outside [{p.min / fr.scale:g}, "
                           f"{p.max / fr.scale:g}] {fr.unit}".rstrip())
        return param, int(round(raw))
    try:
        raw = int(text, 0)
    except ValueError:
        raise BadValue(f"{param}: {text!r} is not an integer (raw protocol values are integers)") from None
    if not p.min <= raw <= p.max:
        raise BadValue(f"{param} = {raw} is outside [{p.min}, {p.max}]")
    return param, raw


def from_raw(name: str, raw: int, clk_hz: int = CLK_HZ) -> tuple[float | int | str, str]:
    """(value as the user named it, unit) for ``get NAME``."""
    param, kind = resolve(name)
    if kind == "special":
        if param == "LAW":
            inv = {v: k for k, v in LAWS.items()}
            return inv.get(raw, str(raw)), ""
        return round(carrier_hz(raw, clk_hz), 3), "Hz"
    if kind == "friendly":
        f = FRIENDLY[name.lower()]
        return (raw if f.scale == 1 else raw / f.scale), f.unit
    return raw, ""
