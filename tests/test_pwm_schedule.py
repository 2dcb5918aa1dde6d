# SPDX-License-Identifier: MIT
"""The PWM block's event model (torqueloop.oracles.pwm_schedule): the
carrier's phase (``first_start``) and the double-buffered command."""

from __future__ import annotations

from torqueloop.oracles.pwm_schedule import PwmChannel, PwmSetting
from torqueloop.spec.bridge import BRAKE, on_pins
from torqueloop.spec.pwm import duty_ticks, full_scale

M = full_scale()


def test_a_command_loaded_at_a_period_start_waits_for_the_next() -> None:
    ch = PwmChannel(PwmSetting(div=2))
    assert ch.fire(0) == BRAKE                  # the period starting at 0 takes command 0
    ch.load(PwmSetting(cmd=512, div=2))
    assert ch.next_event() == 2 * M
    assert ch.fire(2 * M) == on_pins(512)
    assert ch.next_event() == 2 * M + duty_ticks(512, 0, M) * 2


def test_first_start_sets_the_carriers_phase() -> None:
    ch = PwmChannel(PwmSetting(div=2), first_start=100)
    assert ch.fire(0) == BRAKE and ch.next_event() == 100     # no period starts before 100
    ch.load(PwmSetting(cmd=512, div=2))
    assert ch.fire(100) == on_pins(512)                       # the command loaded at 0, taken at 100
    off = 100 + duty_ticks(512, 0, M) * 2
    assert ch.next_event() == off
    assert ch.fire(off) == BRAKE                              # the off phase brakes
    assert ch.next_event() == 100 + 2 * M                     # periods follow from the phase
