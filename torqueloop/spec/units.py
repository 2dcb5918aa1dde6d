# SPDX-License-Identifier: MIT
"""Physical units on the command line, integers on the wire.

Positions: ``6.28rad``, ``4mm``, ``1rev``, ``90deg``, ``8400counts``; speeds
the same per second (``5mm/s``, ``1rev/s``) and accelerations per second
squared (``50mm/s^2``); the board's COUNTS_PER_REV and PITCH_UM (read from
it) convert them, so the tool needs no second copy of the mechanics.  One
rule everywhere: **a bare number is counts** (counts/s, counts/s^2), in
``move``, ``step-test``, ``home`` and the position, limit and speed
parameters alike; a command's ``--unit U`` (when given) makes its bare
numbers U instead.

``pwm_freq`` goes through the divider of eq. (4), which makes only some
carriers: :func:`carrier_choice` names the two around a request and refuses
one further than :data:`PWM_FREQ_TOL` from it unless asked for the nearest.

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
POSITION_UNITS = ("counts", "mm", "rev", "rad", "deg")
#: the largest relative difference between a requested and a stored carrier that `set pwm_freq` accepts
#: without --nearest
PWM_FREQ_TOL = 0.02


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


_POS_RE = re.compile(r"^\s*([-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?)\s*([a-z]*)\s*((?:/\s*s(?:\^?2)?)?)\s*$")
#: what a quantity is per second: 0 a position, 1 a speed, 2 an acceleration
_PER = {0: "", 1: "/s", 2: "/s^2"}
_DIM_NAME = {0: "position", 1: "speed", 2: "acceleration"}


def parse_quantity(text: str, mech: Mechanics, dim: int = 0, default_unit: str = "counts") -> int:
    """``'6.28rad'`` (dim 0), ``'5mm/s'`` (dim 1), ``'50mm/s^2'`` (dim 2) -> counts
    (per second, per second squared).  A bare number is in ``default_unit``."""
    m = _POS_RE.match(text.lower())
    per = _PER[dim]
    if not m:
        raise BadValue(f"cannot read {_DIM_NAME[dim]} {text!r} (examples: 4mm{per}, 1rev{per}, "
                       f"6.28rad{per}, 90deg{per}, 8400counts{per}, or 8400 = counts{per})")
    suffix = m.group(3).replace(" ", "").replace("^", "")
    got = {"": 0, "/s": 1, "/s2": 2}[suffix]
    if got != dim and (m.group(2) or suffix):
        raise BadValue(f"{text!r} is not a {_DIM_NAME[dim]}: give it in mm{per}, rev{per}, rad{per}, "
                       f"deg{per} or counts{per}")
    return mech.to_counts(float(m.group(1)), m.group(2) or default_unit)


def parse_position(text: str, mech: Mechanics, default_unit: str = "counts") -> int:
    """``'6.28rad'`` -> counts.  A bare number is in ``default_unit``."""
    return parse_quantity(text, mech, 0, default_unit)


def carrier_choice(f_hz: float, clk_hz: int = CLK_HZ) -> tuple[int, list[tuple[int, float]]]:
    """(the divider :func:`divider_for` picks for ``f_hz``, the dividers around
    the request with their carriers) - what `set pwm_freq` reports."""
    div = divider_for(f_hz, clk_hz)
    around = sorted({max(1, min(div + d, (1 << 16) - 1)) for d in (-1, 0, 1)})
    near = [(d, carrier_hz(d, clk_hz)) for d in around]
    lo = [x for x in near if x[1] <= f_hz]
    hi = [x for x in near if x[1] > f_hz]
    pair = ([max(lo, key=lambda x: x[1])] if lo else []) + ([min(hi, key=lambda x: x[1])] if hi else [])
    return div, pair


def check_carrier(f_hz: float, clk_hz: int = CLK_HZ, nearest: bool = False) -> int:
    """The divider for ``f_hz``, or BadValue when its carrier is further than
    PWM_FREQ_TOL from the request and ``nearest`` is not set."""
    div, pair = carrier_choice(f_hz, clk_hz)
    got = carrier_hz(div, clk_hz)
    if abs(got - f_hz) > PWM_FREQ_TOL * f_hz and not nearest:
        opts = " or ".join(f"{f:.0f} Hz (FDIV {d})" for d, f in pair)
        raise BadValue(f"pwm_freq: requested {f_hz:g} Hz; the divider makes {opts}; the nearest, "
                       f"{got:.0f} Hz, is {abs(got - f_hz) / f_hz:.1%} away (more than "
                       f"{PWM_FREQ_TOL:.0%}): ask for it, or --nearest to store it")
    return div


@dataclass(frozen=True)
class Friendly:
    """A parameter as people say it: ``value_SI * scale = raw``."""

    param: str
    scale: float
    unit: str
    help: str
    dim: int | None = None     # a position (0), speed (1) or acceleration (2) in counts: takes any unit


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
    "follow_limit": Friendly("FOLLOW_LIMIT", 1, "counts", "following-error fault limit", 0),
    "soft_min": Friendly("SOFT_MIN", 1, "counts", "lowest allowed position", 0),
    "soft_max": Friendly("SOFT_MAX", 1, "counts", "highest allowed position", 0),
    "vmax": Friendly("VMAX", 1, "counts/s", "trapezoid top speed", 1),
    "amax": Friendly("AMAX", 1, "counts/s^2", "trapezoid acceleration", 2),
    "counts_per_rev": Friendly("COUNTS_PER_REV", 1, "counts", "encoder counts per screw turn"),
    "pitch": Friendly("PITCH_UM", 1e6, "m", "ball-screw lead"),
    "stall_cmd": Friendly("STALL_CMD", 1, "steps", "runaway check: command that must move the axis"),
    "stall_time": Friendly("STALL_MS", 1e3, "s", "runaway check: time it has to move it"),
    "limit_sw": Friendly("LIMIT_SW", 1, "", "1 = limit switches wired, 0 = none"),
    "home_vel": Friendly("HOME_VEL", 1, "counts/s", "homing speed", 1),
    "home_pos": Friendly("HOME_POS", 1, "counts", "position given to the home point", 0),
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


def to_raw(name: str, text: str, clk_hz: int = CLK_HZ, mech: Mechanics | None = None,
           nearest: bool = False) -> tuple[str, int]:
    """(protocol parameter, raw integer) for ``set NAME VALUE``; BadValue for
    anything the parameter cannot hold (the message gives its range in the
    unit the value was given in).  ``mech`` converts positions and speeds given
    in mm, rev, rad or deg; ``nearest`` lets pwm_freq store a carrier further
    than PWM_FREQ_TOL from the request."""
    param, kind = resolve(name)
    p = P.PARAMS[param]
    if kind == "special":
        if param == "LAW":
            if text.lower() in LAWS:
                return param, LAWS[text.lower()]
            try:
                v = float(text)
            except ValueError:
                v = -1.0
            if v not in range(p.min, p.max + 1):
                raise BadValue(f"law {text!r}: one of {', '.join(LAWS)} (or 0..3)")
            return param, int(v)
        f = number(text.lower().removesuffix("hz").strip(), name)
        if f <= 0:
            raise BadValue(f"pwm_freq {text} Hz: the carrier must be above 0 Hz")
        return param, check_carrier(f, clk_hz, nearest)
    if kind == "friendly":
        fr = FRIENDLY[name.lower()]
        if fr.dim is not None:
            raw = float(parse_quantity(text, mech or Mechanics(), fr.dim))
            if not p.min <= raw <= p.max:
                raise BadValue(f"{name} {text} is {raw:.0f} {fr.unit}, outside [{p.min}, {p.max}] {fr.unit}")
            return param, int(raw)
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
