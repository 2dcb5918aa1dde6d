# SPDX-License-Identifier: MIT
"""The method's sweeps with the board as the PWM source and a force gauge
(``torqueloop characterize sweep --gauge``; docs/characterization.md, "The
board as the PWM source, with a force gauge").

The board holds each setting the method asks for (torqueloop/host/sweep.py,
:func:`hold_and_read`): step 2's stall reading fully on, the frequency sweep
at 50 % (steps 3-4), then a duty sweep at each carrier step 5 names (step 6)
until step 7 passes (:func:`.session.run_session`).  What only the lab's
instruments can tell - the gauge's force and the supply current - is read
while the board holds the setting: typed at a prompt, or looked up in a
CSV of readings (:class:`ReadingsTable`).  The sweeps are written as the
lab's CSV files (``torqueloop-sweep-1``), so ``characterize run`` gives the
configuration from them.

The duty written for each point is the duty on the bridge pins: the command
through eq. (1) with the axis's PW0 and PWMAX as the board has them (with no
compensation loaded, PW0 = 0, the command itself).
"""

from __future__ import annotations

import csv
import math
import select
import sys
from dataclasses import dataclass
from pathlib import Path
from typing import Callable, TextIO

import numpy as np

from torqueloop.host.client import Client
from torqueloop.host.drive import pin_duty, steps_for
from torqueloop.host.sweep import GaugePoint, hold_and_read
from .data import BenchConstants, Sweep
from .method import MotorResult, Thresholds
from .session import DUTY_PCTS, run_session

#: the paper's frequency sweep, 50-500 Hz (sec. II.B)
PAPER_FREQS_HZ: tuple[float, ...] = tuple(float(f) for f in range(50, 501, 25))
#: the frequency sweep's duty (step 3: 50 %)
HALF_PCT = 50.0


class ReadingError(ValueError):
    """A reading that is missing or not a force and a current."""


@dataclass(frozen=True)
class ReadingsTable:
    """A lab's readings in a CSV file: columns ``sweep`` (stall, frequency or
    duty), ``freq_hz``, ``duty_pct``, ``force_n``, ``current_a``.  A frequency
    row is found by its ``freq_hz`` (within 2 % of the carrier the board made),
    a duty row by its ``duty_pct`` (the command, as given to the tool) and, when
    its ``freq_hz`` is filled in, the carrier; the stall row by its kind."""

    rows: tuple[dict[str, str], ...]
    path: str

    @classmethod
    def load(cls, path: str | Path) -> "ReadingsTable":
        p = Path(path)
        try:
            with p.open(newline="") as f:
                rows = tuple(csv.DictReader(line for line in f if not line.startswith("#")))
        except OSError as e:
            raise ReadingError(f"{path}: {e.strerror}") from None
        need = {"sweep", "freq_hz", "duty_pct", "force_n", "current_a"}
        if not rows or not need <= set(rows[0]):
            raise ReadingError(f"{path}: needs the columns {', '.join(sorted(need))}")
        return cls(rows, str(p))

    def __call__(self, kind: str, carrier_hz: float, duty_pct: float, keepalive: Callable[[], None]
                 ) -> tuple[float, float]:
        for n, r in enumerate(self.rows, 2):
            if r["sweep"].strip() != kind:
                continue
            f = r["freq_hz"].strip()
            if kind == "frequency" and not (f and abs(float(f) - carrier_hz) <= 0.02 * carrier_hz):
                continue
            if kind == "duty" and (abs(float(r["duty_pct"]) - duty_pct) > 1e-6
                                   or (f and abs(float(f) - carrier_hz) > 0.02 * carrier_hz)):
                continue
            try:
                return _reading(r["force_n"], r["current_a"])
            except ReadingError as e:
                raise ReadingError(f"{self.path}:{n}: {e}") from None
        raise ReadingError(f"{self.path}: no {kind} reading for {duty_pct:g} % at {carrier_hz:.1f} Hz")


def _reading(force: str, current: str) -> tuple[float, float]:
    try:
        fv, cv = float(force), float(current)
    except ValueError:
        raise ReadingError(f"{force!r}, {current!r}: give the force in N and the current in A") from None
    if not (math.isfinite(fv) and math.isfinite(cv)) or fv < 0 or cv < 0:
        raise ReadingError(f"force {fv:g} N, current {cv:g} A: neither may be negative")
    return fv, cv


def prompt_reader(inp: TextIO = sys.stdin, out: TextIO = sys.stdout
                  ) -> Callable[[str, float, float, Callable[[], None]], tuple[float, float]]:
    """Ask at the terminal, the link watchdog fed while the lab reads the instruments."""
    def read(kind: str, carrier_hz: float, duty_pct: float, keepalive: Callable[[], None]) -> tuple[float, float]:
        while True:
            out.write(f"{kind} {duty_pct:g} % at {carrier_hz:.1f} Hz: force N and current A? ")
            out.flush()
            while not select.select([inp], [], [], 0.1)[0]:
                keepalive()
            line = inp.readline()
            if not line:
                raise ReadingError("no reading (end of input): sweep abandoned, the axis disabled")
            parts = line.replace(",", " ").split()
            try:
                if len(parts) != 2:
                    raise ReadingError("two numbers, e.g. 48.5 1.2")
                return _reading(*parts)
            except ReadingError as e:
                out.write(f"  {e}\n")
    return read


def _sweep_of(points: list[GaugePoint], kind: str, motor: str, bench: BenchConstants,
              pw0: int, pwmax: int) -> Sweep:
    """The points of one sweep as the lab's record: forces to torque (tau = r F sin theta),
    the duty on the pins (eq. 1)."""
    pts = [p for p in points if p.sweep == kind]
    torque = np.array([float(bench.torque_nm(p.force_n)) for p in pts])
    current = np.array([p.current_a for p in pts])
    if kind == "frequency":
        stall = next(p for p in points if p.sweep == "stall")
        return Sweep("frequency", motor, bench, x=np.array([p.carrier_hz for p in pts]), torque_nm=torque,
                     current_a=current, duty_pct=pin_duty(steps_for(HALF_PCT), pw0, pwmax),
                     stall_torque_nm=float(bench.torque_nm(stall.force_n)), stall_current_a=stall.current_a,
                     force_given=True)
    return Sweep("duty", motor, bench, x=np.array([pin_duty(steps_for(p.duty_pct), pw0, pwmax) for p in pts]),
                 torque_nm=torque, current_a=current, freq_hz=pts[0].carrier_hz, force_given=True)


class SweepAbandoned(Exception):
    def __init__(self, point: GaugePoint) -> None:
        super().__init__(f"{point.sweep} {point.duty_pct:g} % at {point.carrier_hz:.1f} Hz: FAULT {point.fault}")
        self.point = point


def run(c: Client, axis: int, clk_hz: int, out_dir: Path, motor: str, bench: BenchConstants,
        read: Callable[[str, float, float, Callable[[], None]], tuple[float, float]],
        freqs_hz: tuple[float, ...] = PAPER_FREQS_HZ, duty_pcts: tuple[float, ...] = DUTY_PCTS,
        settle_s: float = 0.5, th: Thresholds = Thresholds(), log=None) -> tuple[MotorResult, list[GaugePoint]]:
    """A lab's session with the board as the PWM source; the sweeps in ``out_dir``.
    Raises :class:`SweepAbandoned` when a fault ends a setting (the axis disabled)."""
    pw0, pwmax = c.get_param("PW0", axis), c.get_param("PWMAX", axis)
    points: list[GaugePoint] = []

    def hold(settings: list[tuple[str, float, float]]) -> list[GaugePoint]:
        got = hold_and_read(c, axis, clk_hz, settings, read, settle_s=settle_s, log=log)
        points.extend(got)
        if got and got[-1].fault:
            raise SweepAbandoned(got[-1])
        return got

    def frequency() -> Sweep:
        got = hold([("stall", freqs_hz[0], 100.0)] + [("frequency", f, HALF_PCT) for f in freqs_hz])
        return _sweep_of(got, "frequency", motor, bench, pw0, pwmax)

    def duty(f: float) -> Sweep:
        return _sweep_of(hold([("duty", f, d) for d in duty_pcts]), "duty", motor, bench, pw0, pwmax)

    tag = f"board as the PWM source (axis {axis}), gauge readings by the lab, motor {motor}"
    return run_session(frequency, duty, out_dir, tag, th), points
