# SPDX-License-Identifier: MIT
"""The PWM equations of the paper, defined once (sec. II.C, eq. 1-4).

Frequency divider (eq. 2-4).  The paper writes f_pwm = f_motor * gamma with
gamma = 2^10 (eq. 2), T_pwm = 1/f_pwm (eq. 3) and Count_max = T_pwm / T_FPGA
(eq. 4): Count_max clocks per PWM tick.  The PWM block (rtl/motion/pwm_torque)
makes one carrier period of M = 2^10 - 1 ticks, not 2^10, so that the full
command is a constant high level (docs/pwm_torque.md); the carrier a divisor
gives is therefore

    f_carrier(div) = CLK_HZ / (div * M)                         (pins)

Rounding policy of :func:`divider_for`: of the two integer divisors around
CLK_HZ / (f * M), the one whose carrier is nearest to ``f`` (rounding the
divisor itself is not the same: at 20 kHz the divisors 2 and 3 give 24.4
and 16.3 kHz), clipped to the register's range [1, 2^16 - 1].  The host
tool's ``set pwm_freq``, the characterisation export, the experiment and the
register's reset value all call it.  :func:`paper_hz` is eq. (2) read
literally (gamma = 2^10), for comparison with the paper's numbers.

Dead-zone compensation (eq. 1, as intended; the printed equation is
garbled): with M ticks per period, PW0 the dead-zone edge and PW_F the duty
at full command,

    duty(cmd) = 0                                             cmd == 0
              = min(PW0, PW_F) + round_half_up(|cmd| * max(PW_F - PW0, 0) / M)

with |cmd| saturated at M (eq. 19/25): every non-zero command skips the dead
zone (-PW0, PW0) and maps linearly onto PW0..PW_F.  The RTL (pwm_torque),
its reference model, the firmware-in-the-loop board and the host use this.
"""

from __future__ import annotations

import math

from torqueloop.spec.system import SYSTEM


def full_scale(pwm_bits: int = SYSTEM.pwm_bits) -> int:
    """M: ticks per carrier period, the largest duty and the largest command."""
    return (1 << pwm_bits) - 1


def div_max(div_bits: int = SYSTEM.div_bits) -> int:
    return (1 << div_bits) - 1


def effective_div(div: int) -> int:
    """Clocks between ticks for a divisor register value: 0 and 1 both give a tick every clock."""
    return max(1, div)


def tick_hz(div: int, clk_hz: int = SYSTEM.clk_hz) -> float:
    """The PWM tick rate (the paper's f_pwm) freq_div produces for a divisor."""
    return clk_hz / effective_div(div)


def carrier_hz(div: int, clk_hz: int = SYSTEM.clk_hz, pwm_bits: int = SYSTEM.pwm_bits) -> float:
    """The carrier frequency on the bridge pins for a divisor: M ticks per period."""
    return tick_hz(div, clk_hz) / full_scale(pwm_bits)


def paper_hz(div: int, clk_hz: int = SYSTEM.clk_hz, pwm_bits: int = SYSTEM.pwm_bits) -> float:
    """Eq. (2) read literally: f_motor = f_pwm / 2^bits."""
    return tick_hz(div, clk_hz) / (1 << pwm_bits)


def divider_for(f_hz: float, clk_hz: int = SYSTEM.clk_hz, pwm_bits: int = SYSTEM.pwm_bits,
                div_bits: int = SYSTEM.div_bits) -> int:
    """Count_max (eq. 4) for a wanted carrier: the divisor whose carrier is
    nearest to ``f_hz`` (module docstring), within the register's range."""
    if not (isinstance(f_hz, (int, float)) and math.isfinite(f_hz) and f_hz > 0):
        raise ValueError(f"PWM frequency must be a positive number of Hz, got {f_hz!r}")
    exact = clk_hz / (f_hz * full_scale(pwm_bits))
    hi = div_max(div_bits)
    cands = {min(hi, max(1, math.floor(exact))), min(hi, max(1, math.ceil(exact)))}
    # nearest carrier; on a tie the larger divisor (the lower, gentler carrier)
    return min(sorted(cands, reverse=True), key=lambda d: abs(carrier_hz(d, clk_hz, pwm_bits) - f_hz))


def duty_ticks(cmd: int, pw0: int, pw_max: int, pwm_bits: int = SYSTEM.pwm_bits) -> int:
    """Eq. (1) with saturation: ticks (of M) the bridge is driven for a signed command."""
    m = full_scale(pwm_bits)
    if cmd == 0:
        return 0
    mag = min(abs(cmd), m)
    base = min(pw0, pw_max)
    span = max(pw_max - pw0, 0)
    return base + (2 * mag * span + m) // (2 * m)


def command_for(u: float, pwm_bits: int = SYSTEM.pwm_bits) -> int:
    """The signed PWM command for a torque fraction u = tau / tau_max
    (eq. 23-25): saturated at +-1 (eq. 19), rounded half away from zero."""
    m = full_scale(pwm_bits)
    u = max(-1.0, min(1.0, u))
    return int(math.copysign(math.floor(abs(u) * m + 0.5), u)) if u else 0
