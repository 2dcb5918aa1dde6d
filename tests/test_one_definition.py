# SPDX-License-Identifier: MIT
"""One definition of each equation: the host tool and the characterisation
export choose the same divider (eq. 4), and the host's step-test and the
experiment report measure a trajectory the same way."""

from __future__ import annotations

import math

import numpy as np
import pytest

from torqueloop.characterize import Sweep, axis_config, characterize_motor
from torqueloop.characterize.data import BenchConstants
from torqueloop.host import analysis
from torqueloop.sim import report
from torqueloop.sim.experiment import Trajectory
from torqueloop.spec import units
from torqueloop.spec.pwm import carrier_hz, divider_for
from torqueloop.spec.system import SYSTEM

TAU_MAX = 2.4


def _characterised_at(f_opt: float):
    """A motor whose 50 % torque crosses tau_max / 2 exactly at f_opt and
    whose duty sweep there is linear: step 8 must export f_opt's divider."""
    bench = BenchConstants(0.025, 90.0, 12.0)
    f = np.geomspace(f_opt / 4, f_opt * 4, 21)
    t = TAU_MAX / 2 * (1 + 0.3 * (f_opt - f) / f_opt)
    fs = Sweep("frequency", "m", bench, f, t, t, duty_pct=50.0, stall_torque_nm=TAU_MAX)
    d = np.arange(1.0, 100.0, 2.0)
    ds = Sweep("duty", "m", bench, d, np.maximum(0.0, TAU_MAX * (d - 10) / 90), 0.02 * d, freq_hz=f_opt)
    return axis_config(characterize_motor(fs, [ds]))


@pytest.mark.parametrize("f", [50.0, 200.0, 450.0, 1000.0, 20_000.0])
def test_set_pwm_freq_and_the_characterisation_export_agree(f: float) -> None:
    param, host_div = units.to_raw("pwm_freq", f"{f:g}", nearest=True)
    exported = _characterised_at(f)
    assert param == "FDIV"
    assert exported.pwm_freq_hz == pytest.approx(f, rel=1e-6)
    assert host_div == exported.count_max == divider_for(f)
    assert exported.achieved_hz == pytest.approx(carrier_hz(host_div), rel=1e-6)
    # and the host reads back what the pins run at
    assert units.from_raw("pwm_freq", host_div)[0] == pytest.approx(carrier_hz(host_div), abs=1e-3)


def test_step_test_and_the_experiment_report_measure_alike() -> None:
    """The same trajectory (a damped oscillation settling 3 counts short)
    through `torqueloop step-test`'s code path (counts) and the report's
    (rad): the same overshoot, rise, settling and steady-state error."""
    cpr = SYSTEM.counts_per_turn
    t = np.arange(0, 10, 0.025)
    z, wn = 0.3, 4.0
    wd = wn * math.sqrt(1 - z * z)
    y = 1 - np.exp(-z * wn * t) * (np.cos(wd * t) + z / math.sqrt(1 - z * z) * np.sin(wd * t))
    target = cpr
    x_counts = np.round((target - 3) * y)
    host = analysis.step_figures(t, x_counts, np.full_like(t, target), 0, target, band_min_counts=0.0)
    rad = 2 * math.pi / cpr
    zeros = np.zeros((len(t), 2))
    pos = np.stack([x_counts * rad, x_counts * rad], axis=1)
    tr = Trajectory(t, pos, zeros, zeros, zeros, pos)
    rep = report.axis_metrics(tr, target * rad, 0)
    assert host.overshoot_pct == pytest.approx(rep["overshoot_pct"], rel=1e-9)
    assert host.rise_time_s == pytest.approx(rep["rise_time_s"], rel=1e-9)
    assert host.settling_time_s == pytest.approx(rep["settling_time_s"], rel=1e-9)
    assert host.steady_state_error == pytest.approx(rep["steady_state_error_counts"], rel=1e-9)
    assert host.steady_state_error == pytest.approx(3.0, abs=0.5)
    assert host.rmse * rad == pytest.approx(rep["tracking_rmse_rad"], rel=1e-9)
