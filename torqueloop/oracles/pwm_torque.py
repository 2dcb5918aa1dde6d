# SPDX-License-Identifier: MIT
"""PWM torque block: dead-zone compensated torque command to H-bridge pins.

The mapping (paper eq. 1 as intended, eq. 19/25 saturation) and a
clock-accurate model of rtl/motion/pwm_torque used as the test-bench oracle.
Written from docs/pwm_torque.md, not from the RTL.

Mapping, with M = 2**PWM_BITS - 1 (the full-scale duty, 1023 by default):
  mag  = min(|cmd|, M)                         saturation, eq. (19)/(25)
  base = min(pw0, pw_max)                      the dead-zone edge PW0
  span = max(pw_max - pw0, 0)                  PW_F - PW0
  duty = 0                                       if cmd == 0
       = base + round_half_up(mag * span / M)    otherwise          eq. (1)
so 0 -> 0, +-1 -> PW0 (+1 when span > M/2), +-M -> PW_F, monotonic in |cmd|,
never above pw_max.  A PWM period is M ticks; the pin is high for ``duty``
ticks of it, so duty 0 is constantly low and duty M constantly high.
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass

from torqueloop.spec.pwm import duty_ticks, full_scale

#: clocks from the command/pw0/pw_max inputs to the mapped duty being ready
#: to latch: inputs present at rising edge k are used by a period that starts
#: at edge k + PIPE_CLOCKS or later.
PIPE_CLOCKS = 3


def map_duty(cmd: int, pw0: int, pw_max: int, pwm_bits: int = 10) -> int:
    """Duty (in ticks of an M-tick period) for a signed command: eq. (1) with
    saturation, the project's one definition (torqueloop/spec/pwm.py), which
    this oracle holds the RTL to."""
    return duty_ticks(cmd, pw0, pw_max, pwm_bits)


def map_direction(cmd: int) -> int:
    """1 for a negative (reverse) command, 0 otherwise (zero keeps forward)."""
    return 1 if cmd < 0 else 0


@dataclass(frozen=True)
class PwmInputs:
    """The pwm_torque inputs at one rising edge."""

    tick: int = 0
    cmd: int = 0
    pw0: int = 0
    pw_max: int = 0
    enable: int = 0
    fault: int = 0
    brake_on_fault: int = 0
    dir_mode: int = 0


@dataclass(frozen=True)
class PwmOutputs:
    rpwm: int = 0
    lpwm: int = 0
    r_en: int = 0
    l_en: int = 0
    pwm_out: int = 0
    dir_out: int = 0
    period_start: int = 0
    duty_applied: int = 0
    dir_applied: int = 0
    active: int = 0

    PINS = ("rpwm", "lpwm", "r_en", "l_en", "pwm_out", "dir_out")


def safe_pins(brake: int, dir_mode: int) -> dict[str, int]:
    """The bridge state forced by enable low or fault high (and before the first period).

    Brake: both low sides on.  IBT-2: R_EN = L_EN = 1 with RPWM = LPWM = 0.
    PWM+DIR: enable (r_en, l_en) high with pwm_out = 0.  Coast: every pin 0
    (BTS7960 half-bridges off, the motor free-wheels)."""
    del dir_mode  # the same pins serve both modes in the safe state
    en = 1 if brake else 0
    return dict(rpwm=0, lpwm=0, r_en=en, l_en=en, pwm_out=0, dir_out=0)


def drive_pins(on: int, direction: int, dir_mode: int) -> dict[str, int]:
    """Running bridge pins for one clock: IBT-2 (dir_mode 0) or PWM+DIR (dir_mode 1)."""
    if dir_mode:
        return dict(rpwm=0, lpwm=0, r_en=1, l_en=1, pwm_out=on, dir_out=direction)
    return dict(rpwm=on & (1 - direction), lpwm=on & direction, r_en=1, l_en=1,
                pwm_out=0, dir_out=0)


class PwmTorqueModel:
    """Clock-accurate model of pwm_torque (behaviour of docs/pwm_torque.md).

    * A period is M ticks; the period counter reaches its last value M-1 and
      the next tick starts a new period (``period_start`` is high for the
      clock after that edge).  After reset the first tick starts a period.
    * At a period start the duty and direction mapped from the inputs of
      PIPE_CLOCKS edges earlier are applied (double buffering).
    * The bridge runs only from a period start with enable high and fault
      low; from the edge that samples enable low or fault high it is in the
      safe state and stays there until the next period start with both fine.
    * Pins after an edge show the state after that edge: high while the
      period counter is below the applied duty.
    """

    def __init__(self, pwm_bits: int = 10) -> None:
        self.pwm_bits = pwm_bits
        self.m = full_scale(pwm_bits)
        self.reset()

    def reset(self) -> None:
        self.count = self.m - 1          # the first tick starts a period
        self.duty = 0
        self.direction = 0
        self.running = 0
        self.pipe: deque[tuple[int, int]] = deque([(0, 0)] * PIPE_CLOCKS, maxlen=PIPE_CLOCKS)
        self.out = PwmOutputs()

    def clock(self, i: PwmInputs, rst: int = 0) -> PwmOutputs:
        """Advance one rising edge with inputs ``i``; return the outputs after it."""
        if rst:
            self.reset()
            return self.out
        ready_duty, ready_dir = self.pipe[0]   # mapped PIPE_CLOCKS edges ago
        self.pipe.append((map_duty(i.cmd, i.pw0, i.pw_max, self.pwm_bits), map_direction(i.cmd)))
        stop = (not i.enable) or i.fault
        start = i.tick and self.count == self.m - 1
        if i.tick:
            self.count = 0 if start else self.count + 1
        if start:
            self.duty, self.direction = ready_duty, ready_dir
        if stop:
            self.running = 0
        elif start:
            self.running = 1
        if self.running:
            on = int(self.count < self.duty)
            pins = drive_pins(on, self.direction, i.dir_mode)
        else:
            pins = safe_pins(i.brake_on_fault, i.dir_mode)
        self.out = PwmOutputs(**pins, period_start=int(bool(start)), duty_applied=self.duty,
                              dir_applied=self.direction, active=self.running)
        return self.out
