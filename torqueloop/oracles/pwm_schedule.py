# SPDX-License-Identifier: MIT
"""The PWM block at event level: which IBT-2 pins an axis shows, and when.

One model of freq_div + pwm_torque (docs/freq_div.md, docs/pwm_torque.md) for
every simulation that drives the plant without the RTL: the pure-model loop,
the firmware-law loop and the firmware-in-the-loop board.  Pin edges fall on
the FPGA clock:

* a carrier period is ``div x M`` clocks (M = 2^10 - 1 ticks, eq. 2-4);
* the command (and PW0, PW_F, the divisor, enable) is double-buffered: what
  was loaded last is taken at the next period start;
* the bridge is driven for ``duty_ticks(cmd, PW0, PW_F) x div`` clocks from the
  period start (eq. 1), then shows the off phase: both low sides on (brake),
  as pwm_torque does, or both sides off (``off_phase=COAST``, the other way
  to wire an IBT-2, for comparison only);
* a disabled axis shows its safe state (brake or coast) at once and drives
  again from the first period start after it is enabled.

:class:`PwmChannel` is one axis; :func:`run_until` advances a plant through
the pin changes of several channels; :func:`pin_changes` lists one
channel's changes over a stretch of time.  (The plant's own tests drive it with
arbitrary waveforms instead: sim_models.waveforms.)
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable, Protocol, Sequence

from torqueloop.spec.bridge import BRAKE, Pins, on_pins
from torqueloop.spec.pwm import duty_ticks, effective_div, full_scale
from torqueloop.spec.system import SYSTEM


@dataclass(frozen=True)
class PwmSetting:
    """What the PWM block takes at a period start."""

    cmd: int = 0
    div: int = 1
    pw0: int = 0
    pwmax: int = full_scale()
    enabled: bool = True
    safe: Pins = BRAKE         # pins of a disabled axis


class PwmChannel:
    """One axis's PWM block.  ``load`` a setting; ``fire(now)`` at every
    instant ``next_event()`` names; ``pins`` holds from then on.
    ``first_start``: the clock of the first period start (the carrier's
    phase; on the board it depends on when the divider was last written)."""

    def __init__(self, setting: PwmSetting = PwmSetting(), off_phase: Pins = BRAKE,
                 pwm_bits: int = SYSTEM.pwm_bits, first_start: int = 0) -> None:
        self.m = full_scale(pwm_bits)
        self.off_phase = off_phase
        self.pending = setting
        self.active = setting
        self.next_start = first_start     # clock of the next period start
        self.off_at: int | None = None    # clock the on phase ends in this period
        self.pins: Pins = setting.safe
        self._planned: PwmSetting | None = None
        self._plan: tuple[int, int | None, Pins] = (0, None, setting.safe)

    def load(self, setting: PwmSetting) -> None:
        """Take ``setting`` at the next period start; a disabled setting acts
        at once (pwm_torque: the edge that samples enable low makes the pins
        safe), and the bridge resumes at a period start after re-enabling."""
        self.pending = setting
        if not setting.enabled:
            self.active = setting
            self.off_at = None
            self.pins = setting.safe

    def next_event(self) -> int:
        return self.next_start if self.off_at is None else min(self.next_start, self.off_at)

    def fire(self, now: int) -> Pins:
        """Process the events due at ``now`` (a period start, the end of the on phase)."""
        if self.off_at is not None and self.off_at <= now:
            self.off_at = None
            self.pins = self.off_phase
        if self.next_start <= now:
            s = self.active = self.pending
            if s is not self._planned:       # a setting's periods are all alike
                self._planned, self._plan = s, self._period_of(s)
            period, on, self.pins = self._plan
            self.off_at = None if on is None else now + on
            self.next_start = now + period
        return self.pins

    def _period_of(self, s: PwmSetting) -> tuple[int, int | None, Pins]:
        """(period, clocks the on phase lasts or None if it fills the period
        or is empty, the pins from the period start) of setting ``s``."""
        div = effective_div(s.div)
        period = div * self.m
        on = duty_ticks(s.cmd, s.pw0, s.pwmax) * div if s.enabled else 0
        if not s.enabled:
            pins = s.safe
        elif on == 0 or s.cmd == 0:
            pins = self.off_phase
        else:
            pins = on_pins(s.cmd)
        return period, on if s.enabled and 0 < on < period else None, pins


class Plant(Protocol):
    def advance(self, dt: float, pins: Sequence[Pins]) -> list: ...


class PeriodPlant(Protocol):
    """A plant that takes a stretch's pin changes at once, in ticks of its
    axes' ``tick`` seconds (sim_models.stepper.TwoAxisPlant.run_pins)."""

    axes: Sequence

    def run_pins(self, ticks: int, changes: Sequence[Sequence[tuple[int, Pins]]]) -> None: ...


def run_until(plant: Plant, channels: Sequence[PwmChannel], now: int, end: int,
              clk_hz: int = SYSTEM.clk_hz, on_edges: Callable[[int, list], None] | None = None) -> int:
    """Advance ``plant`` from clock ``now`` to ``end`` through every pin change
    of ``channels``; events at ``end`` itself are processed too, so the pins
    at ``end`` are those of the new phase.  ``on_edges(start_clock, edges)``
    receives what each plant step returned (encoder edges).  Returns the
    number of plant steps taken."""
    steps = 0
    while True:
        pins = [ch.fire(now) for ch in channels]
        if now >= end:
            return steps
        nxt = min([end] + [ch.next_event() for ch in channels])
        edges = plant.advance((nxt - now) / clk_hz, pins)
        steps += 1
        if on_edges is not None and edges:
            on_edges(now, edges)
        now = nxt


def run_pins_until(plant: PeriodPlant, channels: Sequence[PwmChannel], now: int, end: int,
                   clk_hz: int = SYSTEM.clk_hz) -> None:
    """As :func:`run_until`, but the plant takes every pin change from clock
    ``now`` to ``end`` at once (``plant.run_pins``): no encoder edges, for a
    caller that reads the plant only at ``end`` (docs/plant.md, "The fast
    path")."""
    per_clk = round(1.0 / (clk_hz * plant.axes[0].tick))
    plant.run_pins((end - now) * per_clk,
                   [[((c - now) * per_clk, p) for c, p in pin_changes(ch, now, end)] for ch in channels])


def pin_changes(channel: PwmChannel, now: int, end: int) -> list[tuple[int, Pins]]:
    """The pins ``channel`` shows from clock ``now`` to ``end``, as
    (clock, pins) at ``now`` and at each of its events before ``end`` (the
    steps :func:`run_until` takes for this channel); events at ``end`` are
    processed, as there."""
    out: list[tuple[int, Pins]] = []
    while True:
        pins = channel.fire(now)
        if now >= end:
            return out
        out.append((now, pins))
        now = min(end, channel.next_event())
