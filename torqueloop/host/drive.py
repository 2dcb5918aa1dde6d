# SPDX-License-Identifier: MIT
"""Open-loop drive from the host (the firmware's DRIVE command,
docs/protocol.md): a fixed, signed PWM command on one axis for a while,
with the link watchdog fed and the encoder sampled, then the axis disabled.
The bring-up's encoder-sign check (docs/hardware.md) and the characterisation
sweeps (``torqueloop characterize sweep``) run on this.

The duty is given in percent of the full PWM command (1023 steps, the
delta_PW of eq. 1): ``5%`` is 51 steps.  With PW0 = 0 and PWMAX = 1023 (the
defaults) that is the duty on the bridge pins; with a dead-zone compensation
loaded, the bridge sees ``pwm.duty_ticks`` of it (what :func:`pin_duty`
returns)."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Callable

from torqueloop.host.client import Client, ProtocolError, describe_faults
from torqueloop.host.session import BoardTime, board_s
from torqueloop.spec import protocol as P
from torqueloop.spec import pwm
from torqueloop.spec.units import BadValue

#: the drive's samples, seconds of the board's time apart (its telemetry every so many periods)
SAMPLE_S = 0.1
FULL = pwm.full_scale()


def parse_duty(text: str) -> float:
    """``5%``, ``-2.5%`` -> percent.  A bare number is refused: a duty without
    its unit is too easy to give as steps (1023 = 100 %) by mistake."""
    t = text.strip()
    if not t.endswith("%"):
        raise BadValue(f"duty {text!r}: give it in percent of the full command, e.g. 5% or -5%")
    try:
        v = float(t[:-1])
    except ValueError:
        raise BadValue(f"duty {text!r} is not a number of percent") from None
    if not math.isfinite(v) or not -100.0 <= v <= 100.0:
        raise BadValue(f"duty {text} is outside [-100%, 100%]")
    return v


def steps_for(percent: float) -> int:
    """The signed PWM command for a duty in percent, rounded half away from zero (pwm.command_for)."""
    return pwm.command_for(percent / 100.0)


def pin_duty(steps: int, pw0: int, pwmax: int) -> float:
    """The duty the bridge sees for command ``steps``, percent (eq. 1 with PW0 and PWMAX)."""
    return 100.0 * pwm.duty_ticks(steps, pw0, pwmax) / FULL


@dataclass
class DriveResult:
    axis: int
    steps: int
    start_counts: int
    end_counts: int
    seconds: float
    faults: int = 0                 # faults that tripped during the drive
    interrupted: bool = False
    samples: list[dict] = field(default_factory=list)   # t_s, position, velocity_cps, pwm_cmd

    @property
    def moved(self) -> int:
        return self.end_counts - self.start_counts


def check_ready(c: Client, axis: int, steps: int) -> dict[str, int]:
    """What the board would refuse, asked before the axis is enabled (a
    refused drive must not leave it enabled).  Returns the axis's status."""
    st = c.status(axis)
    limit = c.get_param("CMD_LIMIT", axis)
    if abs(steps) > limit:
        raise BadValue(f"{100 * steps / FULL:+g}% is {steps} steps, above axis {axis}'s CMD_LIMIT of {limit} "
                       f"steps ({100 * limit / FULL:.1f}%)")
    blocking = st["faults"] & ~P.DIRECTIONAL_FAULTS
    if blocking:
        raise ProtocolError(f"axis {axis} has latched faults: {describe_faults(blocking)}; "
                            "`torqueloop clear-fault` first")
    if P.HOME_STATE.get(st["home"]) == "homing":
        raise ProtocolError(f"axis {axis} is homing: `torqueloop stop` first")
    lim = st["limits"] | (P.LIMIT_BITS["neg"] if st["faults"] & P.FAULT["LIMIT_NEG"] else 0) \
        | (P.LIMIT_BITS["pos"] if st["faults"] & P.FAULT["LIMIT_POS"] else 0)
    if (lim & P.LIMIT_BITS["pos"] and steps > 0) or (lim & P.LIMIT_BITS["neg"] and steps < 0):
        raise ProtocolError(f"axis {axis}: the limit switch at that end is tripped; drive away from it")
    return st


def drive(c: Client, axis: int, steps: int, seconds: float,
          on_sample: Callable[[dict], None] | None = None, stop_when: Callable[[dict], bool] | None = None,
          disable: bool = True) -> DriveResult:
    """Enable ``axis`` (if it is not), drive it open-loop at ``steps`` for
    ``seconds`` of the board's time (its telemetry's clock,
    :class:`~torqueloop.host.session.BoardTime`: a simulated board slower
    than real time is driven just as long), sampled from the telemetry every
    SAMPLE_S of it (or until ``stop_when(sample)``), then disable it
    (``disable``) or hold.  A fault ends the drive early (``faults`` in the
    result); Ctrl-C ends it with ``interrupted``.  Either way the axis is
    disabled before this returns or raises."""
    st = check_ready(c, axis, steps)
    start = st["position"]
    c.enable(1 << axis, True)
    res = DriveResult(axis, steps, start, start, 0.0)
    t0_us: int | None = None            # the first sample's board time: the drive in effect

    def sample(rec: dict) -> None:
        nonlocal t0_us
        a = rec["axes"][axis]
        if t0_us is None:
            # through `serve` records sampled before the DRIVE (the axis not yet enabled or
            # driven) can still arrive after its reply: the drive's samples start where it shows
            if not (a["enabled"] and a["pwm_cmd"] == steps) and not a["faults"] & ~st["faults"]:
                return
            t0_us = rec["time_us"]
        smp = {"t_s": round(board_s(t0_us, rec["time_us"]), 3), "position": a["position"],
               "velocity_cps": a["velocity_q8"] / 256, "pwm_cmd": a["pwm_cmd"], "enabled": a["enabled"],
               "faults": a["faults"]}
        res.samples.append(smp)
        res.end_counts = a["position"]
        if on_sample:
            on_sample(smp)

    def ends(rec: dict) -> bool:
        a = rec["axes"][axis]               # a new fault disables the axis it trips on
        return bool(a["faults"] & ~st["faults"]) or (t0_us is not None and (
            not a["enabled"] or board_s(t0_us, rec["time_us"]) >= seconds
            or (stop_when is not None and stop_when(res.samples[-1]))))

    try:
        with BoardTime(c, record_s=SAMPLE_S) as bt:
            c.drive(axis, steps)
            # the time counted from the drive's first sample (ends); the hold's own bound a second
            # later, should the drive never show (the axis disabled by another client meanwhile)
            bt.hold(seconds + 1.0, on_record=sample, until=ends)
    except KeyboardInterrupt:
        res.interrupted = True
    finally:
        if disable:
            c.enable(1 << axis, False)
        else:
            c.stop(1 << axis)
        res.seconds = res.samples[-1]["t_s"] if res.samples else 0.0
    s = c.status(axis)
    res.end_counts = s["position"]
    res.faults |= s["faults"] & ~st["faults"]
    return res

