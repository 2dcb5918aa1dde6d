# SPDX-License-Identifier: MIT
"""The simulated bench's session logic (torqueloop.characterize.simbench) on
a dynamometer whose answers are known in closed form, with the pin
waveforms the cores produce (source "model"; the RTL source is checked
against the same waveforms in tb/char_bench).

The test dynamometer: a stalled motor whose bridge stretches every pulse by
T_S (turn-off delay longer than turn-on), with a friction dead zone D0:
    torque = K (d + T_S f - D0), clipped at 0, for 0 < d < 1;
    torque = K (1 - D0) when constantly on (no switching, no stretch).
The frequency sweep runs at h = 512/1023 = 50.05 % (the nearest the
1023-count period gets to 50 %), so step 5's target is tau_max h, met where
h + T_S f - D0 = (1 - D0) h, i.e.
    f* = D0 (1 - h) / T_S,
and the duty sweep there has its dead-zone edge at D0 - T_S f*.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from torqueloop.characterize import load_config
from torqueloop.characterize.config import axis_config, build_config
from torqueloop.spec.charconfig import write_config
from torqueloop.characterize.method import Thresholds
from torqueloop.characterize.simbench import PinWaveform, Reading, SweepPlan, model_waveform, run_bench

K, D0, T_S, R = 2.5, 0.10, 120e-6, 0.025
HALF = 512 / 1023
F_STAR = D0 * (1 - HALF) / T_S  # 416.3 Hz


def stretch_dyno(w: PinWaveform) -> Reading:
    d = w.high_s / w.period_s
    tau = K * (1 - D0) if d >= 1.0 else max(0.0, K * (d + T_S * w.freq_hz - D0))
    return Reading(force_n=tau / R, current_a=2.27 * min(1.0, d + T_S * w.freq_hz), current_std_a=0.0)


def test_model_waveform_is_the_cores_period_and_duty():
    w = model_waveform(109, 512)
    assert w.period_s == pytest.approx(109 * 1023 / 50e6)
    assert w.high_s == pytest.approx(109 * 512 / 50e6)
    assert model_waveform(109, 1023).high_s == pytest.approx(w.period_s)
    assert model_waveform(109, 0).high_s == 0.0


def test_simulated_session_finds_the_known_frequency_and_dead_zone(tmp_path: Path):
    r = run_bench(stretch_dyno, tmp_path / "x", "x", SweepPlan(wheel_radius_m=R))
    assert r.status == "pass", r.message
    assert r.chosen.freq_hz == pytest.approx(F_STAR, rel=1e-6)  # torque is linear in f: exact
    lin = r.linearity
    # the duty sweep ran at the board frequency nearest f*, not f* itself
    f_board = lin.freq_hz
    assert abs(f_board / F_STAR - 1) < 0.005
    assert lin.pw0_pct == pytest.approx(100 * (D0 - T_S * f_board), abs=1e-6)
    assert lin.pwf_pct == pytest.approx(100 * (1 - T_S * f_board), abs=1e-6)
    files = sorted(p.name for p in (tmp_path / "x").iterdir())
    assert files[-1] == "freq_sweep.csv" and files[0].startswith("duty_sweep_")

    a = axis_config(r, base_dir=tmp_path)
    write_config(tmp_path / "cfg.json", build_config({"x": a}, Thresholds()))
    got = load_config(tmp_path / "cfg.json").axes["x"]
    pw0_exact = (D0 - T_S * f_board) * 1023  # counts, rounded up in the file
    assert got.pw0_counts - 1 < pw0_exact <= got.pw0_counts
    assert got.provenance["inputs"][0]["file"] == "x/freq_sweep.csv"
