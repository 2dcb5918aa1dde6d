"""Frequency divider: the PWM tick rate from the system clock (paper eq. 2-4).

Plain functions for the firmware configuration and the characterisation
flow (which divisor gives a wanted motor PWM frequency, and how far off the
integer divisor lands), plus a clock-accurate model of rtl/motion/freq_div
used as the test-bench oracle.  Written from docs/freq_div.md, not from the
RTL.

Terms (paper section II.C):
  f_pwm   = f_motor * gamma,  gamma = 2**PWM_BITS          eq. (2)
  T_pwm   = 1 / f_pwm                                       eq. (3)
  Count_max = round(T_pwm / T_clk) = round(CLK_HZ / f_pwm)  eq. (4)

The tick then runs at CLK_HZ / Count_max.  The PWM block (pwm_torque) makes
one carrier period from 2**PWM_BITS - 1 ticks (so that full scale is a
constant high level, see docs/pwm_torque.md), hence the carrier frequency
actually reached is CLK_HZ / (Count_max * (2**PWM_BITS - 1)).
"""

from __future__ import annotations

from dataclasses import dataclass

CLK_HZ_DE0_CV = 50_000_000


@dataclass(frozen=True)
class FreqDivParams:
    """The generics of rtl/motion/freq_div (defaults: the DE0-CV build)."""

    clk_hz: int = CLK_HZ_DE0_CV
    pwm_bits: int = 10
    div_bits: int = 16
    default_motor_hz: int = 450   # the paper's optimum for motor 1 (section VI.A)

    @property
    def div_max(self) -> int:
        return (1 << self.div_bits) - 1

    @property
    def default_div(self) -> int:
        """The reset value of the divisor register: Count_max of the default frequency."""
        return count_max(self.default_motor_hz, self.clk_hz, self.pwm_bits, self.div_bits)


def _round_half_up(num: int, den: int) -> int:
    return (2 * num + den) // (2 * den)


def count_max(f_motor_hz: float, clk_hz: int = CLK_HZ_DE0_CV, pwm_bits: int = 10,
              div_bits: int = 16) -> int:
    """Count_max of eq. (4) for a wanted motor PWM frequency, rounded half up and
    clipped to the divisor register's range [1, 2**div_bits - 1]."""
    if f_motor_hz <= 0:
        raise ValueError(f"motor frequency must be positive, got {f_motor_hz}")
    f_pwm = f_motor_hz * (1 << pwm_bits)                      # eq. (2)
    if float(f_motor_hz).is_integer():
        n = _round_half_up(clk_hz, int(f_pwm))                # exact for integer Hz
    else:
        n = int(clk_hz / f_pwm + 0.5)                         # eq. (3)-(4)
    return max(1, min(n, (1 << div_bits) - 1))


def effective_div(div: int) -> int:
    """Clocks between ticks for a divisor register value: 0 and 1 both give a tick every clock."""
    return max(1, div)


def tick_hz(div: int, clk_hz: int = CLK_HZ_DE0_CV) -> float:
    """The tick (f_pwm) frequency freq_div produces for a divisor value."""
    return clk_hz / effective_div(div)


def carrier_hz(div: int, clk_hz: int = CLK_HZ_DE0_CV, pwm_bits: int = 10) -> float:
    """The PWM carrier (motor) frequency pwm_torque reaches: 2**pwm_bits - 1 ticks per period."""
    return tick_hz(div, clk_hz) / ((1 << pwm_bits) - 1)


@dataclass(frozen=True)
class FrequencyError:
    f_target_hz: float
    count_max: int
    f_eq2_hz: float        # CLK / (Count_max * 2**PWM_BITS): the paper's gamma
    f_carrier_hz: float    # CLK / (Count_max * (2**PWM_BITS - 1)): what the pins show
    error_eq2: float       # relative error of f_eq2_hz
    error_carrier: float   # relative error of f_carrier_hz


def frequency_error(f_motor_hz: float, clk_hz: int = CLK_HZ_DE0_CV, pwm_bits: int = 10,
                    div_bits: int = 16) -> FrequencyError:
    """How far the integer divisor of eq. (4) lands from the wanted motor frequency."""
    n = count_max(f_motor_hz, clk_hz, pwm_bits, div_bits)
    f_eq2 = clk_hz / (n * (1 << pwm_bits))
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
