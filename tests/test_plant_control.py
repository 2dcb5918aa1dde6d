# SPDX-License-Identifier: MIT
"""Pure-model closed loop (torqueloop.sim.model_loop)."""

from __future__ import annotations

import pytest

from torqueloop.sim.model_loop import TABLE1, LoopConfig, run_loop
from torqueloop.spec.metrics import step_metrics
from torqueloop.spec.pwm import command_for, duty_ticks


def test_command_saturates_and_the_pwm_skips_the_dead_zone():
    """eq. (19)/(23)-(25): the torque fraction becomes a 10-bit command,
    saturated; eq. (1): the PWM maps any non-zero command past PW0."""
    assert command_for(0.0) == 0
    assert command_for(10.0 / 2.4) == 1023           # eq (19): saturation
    assert command_for(-10.0 / 2.4) == -1023
    assert command_for(0.5) == 512 and command_for(-0.5) == -512    # half away from zero
    pw0 = round(0.2 * 1023)
    assert pw0 <= duty_ticks(1, pw0, 1023) <= pw0 + 1   # the smallest command starts at PW0
    assert duty_ticks(-512, pw0, 1023) == pw0 + round(512 * (1023 - pw0) / 1023)
    assert duty_ticks(1023, pw0, 1023) == 1023


def test_p_control_settles_axis_x_on_one_screw_turn():
    """Paper's step (6.28 rad) with Table 1's P gain on axis x: settles within
    15 encoder counts in 4 s and the encoder tracks the model's angle."""
    r = run_loop(LoopConfig(t_end_s=4.0, gains=TABLE1["P"]))
    m = step_metrics(r.t, r.x_meas[:, 0], 6.28)
    assert abs(m.final_error) < 0.01
    assert 0.2 < m.rise_time_s < 1.0
    assert abs(r.x_meas[-1, 0] - r.x_true[-1, 0]) < 2 * 2 * 3.141592653589793 / 8400
    assert r.table_mm[-1, 0] == pytest.approx(4.0, abs=0.05)


def test_pid_anti_windup_matches_the_firmware_law():
    """Axis z saturates for over a second after the step: with the firmware's
    anti-windup its overshoot stays near the RTL-in-the-loop 56 %; the plain
    eq. (22) integral winds up and doubles it."""
    over = {}
    for aw in (True, False):
        r = run_loop(LoopConfig(t_end_s=6.0, gains=TABLE1["PID"], anti_windup=aw))
        over[aw] = step_metrics(r.t, r.x_meas[:, 1], 6.28).overshoot_pct
    assert 50.0 < over[True] < 62.0
    assert over[False] > over[True] + 30.0
