# SPDX-License-Identifier: MIT
"""The system constants (``system.toml`` beside this module), loaded once.

``SYSTEM`` holds them as frozen dataclasses; everything else reads them from
here: ``SYSTEM.clk_hz``, ``SYSTEM.pwm_full`` (ticks per carrier period),
``SYSTEM.counts_per_turn``, ``SYSTEM.axes[0].tau_max_mnm``,
``SYSTEM.table1["PID"][1].ki`` ...
"""

from __future__ import annotations

import math
import tomllib
from dataclasses import dataclass
from pathlib import Path
from typing import Any

SYSTEM_TOML = Path(__file__).resolve().with_name("system.toml")

LAWS = ("P", "PD", "PID")


class SystemError_(ValueError):
    """system.toml is missing a key or has a value that breaks a rule."""


@dataclass(frozen=True)
class Gains:
    """One axis's gains of one law (Table 1, physical units)."""

    kp: float            # N m / rad
    kd: float = 0.0      # N m s / rad
    ki: float = 0.0      # N m / (rad s)

    def micro(self) -> tuple[int, int, int]:
        """The protocol's units: micro N m per rad, per rad/s, per rad s."""
        return round(self.kp * 1e6), round(self.kd * 1e6), round(self.ki * 1e6)


@dataclass(frozen=True)
class AxisConstants:
    name: str
    tau_max_mnm: int     # torque at full command, milli N m (the paper's tau_max)
    pwm_hz: float        # the paper's optimal carrier for this axis's motor

    @property
    def tau_max_N_m(self) -> float:
        return self.tau_max_mnm / 1000.0


@dataclass(frozen=True)
class System:
    clk_hz: int
    pwm_bits: int
    div_bits: int
    working_hz: int
    bridge_max_hz: int
    counts_per_motor_rev: int
    gear_ratio: float
    lead_um: int
    period_us: int
    vel_filter: float
    step_rad: float
    t_end_s: float
    axes: tuple[AxisConstants, ...]
    table1: dict[str, tuple[Gains, ...]]

    @property
    def pwm_full(self) -> int:
        """Ticks of one carrier period and the largest command: 2^bits - 1
        (pwm_torque makes full scale a constant high level, docs/pwm_torque.md)."""
        return (1 << self.pwm_bits) - 1

    @property
    def counts_per_turn(self) -> int:
        """Encoder counts per screw (output-shaft) turn."""
        return round(self.counts_per_motor_rev * self.gear_ratio)

    @property
    def counts_per_rad(self) -> float:
        return self.counts_per_turn / (2 * math.pi)

    @property
    def tau_max_N_m(self) -> tuple[float, ...]:
        return tuple(a.tau_max_N_m for a in self.axes)

    @property
    def pwm_hz(self) -> tuple[float, ...]:
        return tuple(a.pwm_hz for a in self.axes)


def _get(d: dict, key: str, kind: type | tuple[type, ...], where: str) -> Any:
    if key not in d:
        raise SystemError_(f"system.toml: [{where}] has no '{key}'")
    v = d[key]
    if isinstance(v, bool) or not isinstance(v, kind):
        raise SystemError_(f"system.toml: {where}.{key} = {v!r} is not a {getattr(kind, '__name__', kind)}")
    return v


def _positive(v: float, name: str) -> float:
    if not v > 0:
        raise SystemError_(f"system.toml: {name} = {v} must be positive")
    return v


def parse(data: dict) -> System:
    num = (int, float)
    clock, pwm = data.get("clock", {}), data.get("pwm", {})
    enc, mech, ctl = data.get("encoder", {}), data.get("mechanics", {}), data.get("control", {})
    axes = tuple(
        AxisConstants(name=_get(a, "name", str, f"axis {i}"),
                      tau_max_mnm=int(_positive(_get(a, "tau_max_mnm", int, f"axis {i}"), f"axis {i}.tau_max_mnm")),
                      pwm_hz=float(_positive(_get(a, "pwm_hz", num, f"axis {i}"), f"axis {i}.pwm_hz")))
        for i, a in enumerate(data.get("axis", [])))
    if len(axes) != 2:
        raise SystemError_(f"system.toml: {len(axes)} [[axis]] tables; the board has 2 axes")
    t1 = data.get("table1", {})
    table1: dict[str, tuple[Gains, ...]] = {}
    for law in LAWS:
        rows = t1.get(law)
        if not isinstance(rows, list) or len(rows) != len(axes):
            raise SystemError_(f"system.toml: table1.{law} must list {len(axes)} axes' gains")
        gains = []
        for i, r in enumerate(rows):
            unknown = set(r) - {"kp", "kd", "ki"}
            if unknown:
                raise SystemError_(f"system.toml: table1.{law}[{i}] has unknown keys {sorted(unknown)}")
            g = Gains(**{k: float(v) for k, v in r.items()})
            if min(g.kp, g.kd, g.ki) < 0:
                raise SystemError_(f"system.toml: table1.{law}[{i}]: gains must not be negative")
            gains.append(g)
        table1[law] = tuple(gains)
    s = System(
        clk_hz=int(_positive(_get(clock, "clk_hz", int, "clock"), "clock.clk_hz")),
        pwm_bits=int(_positive(_get(pwm, "bits", int, "pwm"), "pwm.bits")),
        div_bits=int(_positive(_get(pwm, "div_bits", int, "pwm"), "pwm.div_bits")),
        bridge_max_hz=int(_positive(_get(pwm, "bridge_max_hz", int, "pwm"), "pwm.bridge_max_hz")),
        working_hz=int(_positive(_get(pwm, "working_hz", int, "pwm"), "pwm.working_hz")),
        counts_per_motor_rev=int(_positive(_get(enc, "counts_per_motor_rev", int, "encoder"), "encoder.counts_per_motor_rev")),
        gear_ratio=float(_positive(_get(mech, "gear_ratio", num, "mechanics"), "mechanics.gear_ratio")),
        lead_um=int(_positive(_get(mech, "lead_um", int, "mechanics"), "mechanics.lead_um")),
        period_us=int(_positive(_get(ctl, "period_us", int, "control"), "control.period_us")),
        vel_filter=float(_get(ctl, "vel_filter", num, "control")),
        step_rad=float(_get(ctl, "step_rad", num, "control")),
        t_end_s=float(_positive(_get(ctl, "t_end_s", num, "control"), "control.t_end_s")),
        axes=axes,
        table1=table1,
    )
    if abs(s.counts_per_motor_rev * s.gear_ratio - s.counts_per_turn) > 1e-9:
        raise SystemError_("system.toml: counts_per_motor_rev x gear_ratio must be a whole number of counts")
    if not 0 < s.vel_filter <= 1:
        raise SystemError_(f"system.toml: control.vel_filter = {s.vel_filter} must be in (0, 1]")
    return s


def load(path: Path = SYSTEM_TOML) -> System:
    with open(path, "rb") as f:
        return parse(tomllib.load(f))


SYSTEM = load()
