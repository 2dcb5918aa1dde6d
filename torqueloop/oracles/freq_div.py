# SPDX-License-Identifier: MIT
"""Frequency divider: a clock-accurate model of rtl/motion/freq_div, the
test-bench oracle.  Written from docs/freq_div.md, not from the RTL.

The equations (eq. 2-4: which divisor gives which carrier, and the rounding
policy) are torqueloop.spec.pwm's, the one definition the host tool, the
characterisation export and the experiment use too; this module re-exports
them for the benches and adds how far the integer divisor lands.
"""

from __future__ import annotations

from dataclasses import dataclass

from torqueloop.spec.pwm import carrier_hz, div_max, divider_for, effective_div, paper_hz, tick_hz
from torqueloop.spec.system import SYSTEM

__all__ = ["FreqDivParams", "FreqDivModel", "FrequencyError", "frequency_error", "carrier_hz", "count_max",
           "effective_div", "tick_hz"]


@dataclass(frozen=True)
class FreqDivParams:
    """The generics of rtl/motion/freq_div (defaults: the DE0-CV build)."""

    clk_hz: int = SYSTEM.clk_hz
    pwm_bits: int = SYSTEM.pwm_bits
    div_bits: int = SYSTEM.div_bits
    #: the reset value of the divisor register (the board's: the FDIV register's
    #: reset, Count_max of the paper's motor-1 optimum, section VI.A)
    default_div: int = divider_for(SYSTEM.axes[0].pwm_hz)

    @property
    def div_max(self) -> int:
        return div_max(self.div_bits)


def count_max(f_motor_hz: float, clk_hz: int = SYSTEM.clk_hz, pwm_bits: int = SYSTEM.pwm_bits,
              div_bits: int = SYSTEM.div_bits) -> int:
    """Count_max of eq. (4) for a wanted carrier: torqueloop.spec.pwm.divider_for."""
    return divider_for(f_motor_hz, clk_hz, pwm_bits, div_bits)


@dataclass(frozen=True)
class FrequencyError:
    f_target_hz: float
    count_max: int
    f_eq2_hz: float        # CLK / (Count_max * 2**PWM_BITS): the paper's gamma
    f_carrier_hz: float    # CLK / (Count_max * (2**PWM_BITS - 1)): what the pins show
    error_eq2: float       # relative error of f_eq2_hz
    error_carrier: float   # relative error of f_carrier_hz


def frequency_error(f_motor_hz: float, clk_hz: int = SYSTEM.clk_hz, pwm_bits: int = SYSTEM.pwm_bits,
                    div_bits: int = SYSTEM.div_bits) -> FrequencyError:
    """How far the integer divisor of eq. (4) lands from the wanted motor frequency."""
    n = count_max(f_motor_hz, clk_hz, pwm_bits, div_bits)
    f_eq2 = paper_hz(n, clk_hz, pwm_bits)
    f_car = carrier_hz(n, clk_hz, pwm_bits)
    return FrequencyError(f_motor_hz, n, f_eq2, f_car,
                          f_eq2 / f_motor_hz - 1.0, f_car / f_motor_hz - 1.0)


class FreqDivModel:
    """Clock-accurate model of freq_div.

    Per rising edge: a divisor write (div_we) stores div_in, seen by the
    counter from the next edge on.  ``tick`` is a registered one-clock pulse
    that comes every effective_div(div) clocks; if the divisor is lowered
    below the current count, the next tick comes on the next edge (no wait for
    a counter wrap).  Synchronous reset: divisor = default, count = 0, no tick.
    """

    def __init__(self, p: FreqDivParams = FreqDivParams()) -> None:
        self.p = p
        self.reset()

    def reset(self) -> None:
        self.div = self.p.default_div
        self.count = 0
        self.tick = 0

    def clock(self, rst: int = 0, div_we: int = 0, div_in: int = 0) -> tuple[int, int]:
        """Advance one rising edge; return (tick, div) as seen after it."""
        if rst:
            self.reset()
            return self.tick, self.div
        wrap = self.count + 1 >= self.div
        self.tick = int(wrap)
        self.count = 0 if wrap else self.count + 1
        if div_we:
            self.div = div_in & self.p.div_max
        return self.tick, self.div
