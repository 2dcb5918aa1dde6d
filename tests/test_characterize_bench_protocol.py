"""The simulated bench's protocol choices (docs/characterization.md): readings
that wait until they have converged, and the paper's dead zone as a motion
threshold on the applied system beside the project's torque intercept."""

from __future__ import annotations

import dataclasses

import pytest

from sim_models import axis as ax
from sim_models.dyno import RopeDynamometer
from sim_models.variants import load_variant
from torqueloop.characterize.method import MethodError, motion_dead_zone
from torqueloop.characterize.simbench import (CLK_HZ, PWM_BITS, MotionRamp, model_waveform, record_motion_ramp,
                                              rope_config)
from torqueloop.spec.pwm import divider_for, full_scale

# ---------------------------------------------------------------- the paper's dead zone


def test_motion_dead_zone_reads_start_and_stop_from_a_ramp() -> None:
    dz = motion_dead_zone([1, 2, 3, 4], [0, 0, 1, 5], [3, 2, 1], [4, 2, 0], 2, 450.0, 1)
    assert (dz.start_pct, dz.stop_pct, dz.pw0_pct, dz.hysteresis_pct) == (4.0, 2.0, 2.0, 2.0)
    with pytest.raises(MethodError, match="never moved up to 4 % duty"):
        motion_dead_zone([1, 2, 3, 4], [0, 0, 1, 1], [], [], 2, 450.0, 1)
    with pytest.raises(MethodError, match="still moved at 1 % duty"):
        motion_dead_zone([1, 2], [0, 3], [1], [3], 2, 450.0, 1)
    with pytest.raises(MethodError, match="must rise"):
        motion_dead_zone([2, 1], [0, 3], [1], [0], 2, 450.0, 1)


def test_paper_dead_zone_is_the_breakaway_rising_and_the_coulomb_level_falling() -> None:
    """Motor friction alone (breakaway T_s, sliding T_c), table friction off,
    and an armature slow enough (L x 100) that the 5 kHz ripple is below one
    duty step: the ramp starts the motor at the first step above
    T_s R / (k_t V) and it stops one step below T_c R / (k_t V), in both
    directions; the held-motor intercept would put PW0 at 0 (no brush drop)."""
    p = load_variant("lab", ("brush_drop", "gear_efficiency", "energy_consistent", "bridge_timing", "brush_law",
                             "winding_thermal", "gear_backlash"))
    a = p.axes[0].replace(table_coulomb_N=0.0, inductance_H=100 * p.axes[0].inductance_H)
    p = dataclasses.replace(p, axes=(a, p.axes[1]))
    c = ax.AxisConsts.build(a, p.bridge)
    per_pct = c.kt * p.bridge.supply_V / c.R / 100.0          # motor torque per % duty
    d_s, d_c = a.motor_static_N_m / per_pct, a.motor_coulomb_N_m / per_pct
    ramp = MotionRamp(step_counts=4, dwell_s=0.4)
    step = 100.0 * ramp.step_counts / full_scale(PWM_BITS)
    n = divider_for(5000.0, CLK_HZ, PWM_BITS)
    for direction in (1, -1):
        rec = record_motion_ramp(p, 0, n, direction, ramp)
        assert all(m * direction >= 0 for m in rec[1] + rec[3])   # it moves the way it is driven
        dz = motion_dead_zone(*rec, threshold_counts=ramp.threshold_counts,
                              freq_hz=model_waveform(n, 1).freq_hz, direction=direction)
        assert d_s <= dz.start_pct < d_s + step, (dz, d_s)
        assert d_c <= dz.stop_pct < d_c + step, (dz, d_c)
        assert dz.hysteresis_pct > 0


# ---------------------------------------------------------------- readings that converge


def test_rope_config_refuses_a_bad_settle() -> None:
    assert rope_config(1.0).settle_s == 1.0 and rope_config(1.0).settle_rule == "fixed"
    assert rope_config("converged").settle_rule == "converged"
    with pytest.raises(ValueError, match="positive number of seconds or 'converged'"):
        rope_config(0)


def test_a_converged_reading_waits_out_the_wind_up_a_fixed_settle_cuts_short() -> None:
    """lab-2025, motor x at 1.1 kHz, 50 %: the 0.3 s settle reads the rope
    still winding up; the converged rule holds longer (and says how long),
    and its reading agrees with a long fixed settle to within twice its
    criterion (0.1 % of the stall force across 1 s)."""
    p = load_variant("lab-2025")
    a = p.axes[0]
    n = divider_for(1111.0, CLK_HZ, PWM_BITS)
    w = model_waveform(n, (full_scale(PWM_BITS) + 1) // 2)
    read = {}
    for settle in (0.3, "converged", 4.0):
        d = RopeDynamometer(a, p, rope_config(settle))
        read[settle] = d.trace(w.segments, w.period_s)
    stall = d.stall_force_N()
    conv = read["converged"]
    assert conv.converged and 1.0 < conv.settle_s < 4.0, conv
    assert read[4.0].force_mean_N - read[0.3].force_mean_N > 0.01 * stall
    assert abs(conv.force_mean_N - read[4.0].force_mean_N) < 0.002 * stall
