# SPDX-License-Identifier: MIT
"""``torqueloop tune``'s velocity and acceleration feed-forward (KVFF_Q16,
KAFF_Q16), designed from the plant file's identifiable keys and checked on a
trapezoid move on the fast model (the firmware's law bit for bit, the PWM
block's events, the plant's stepper).

The plant is tests/test_tune.py's: lab-2025 with its rotor friction scaled
by 1.25 and its inertia by 0.8, which the design only sees through the plant
file's identifiable keys."""

import json
import tomllib

import numpy as np
import pytest

from scaled_plant import scaled_lab_2025
from sim_models.variants import PlantSpec
from torqueloop import cli
from torqueloop.host.tune import tune_axis
from torqueloop.host.tunedesign import Wish
from torqueloop.sim import experiment, tuneverify

#: what the feed-forward must buy on the verification trapezoid: the peak following error at most this
#: share of the same move's without it
MAX_SHARE = 0.5
#: the trapezoid (one screw turn) ends by 1.45 s on x and 2.25 s on z; the record runs past it
VERIFY_S = 2.5
MAX_OVERSHOOT_PCT, MAX_ERROR_COUNTS = 2.0, 2.0


@pytest.fixture(scope="module")
def plant_file(tmp_path_factory):
    return scaled_lab_2025(tmp_path_factory.mktemp("plant"))[1]


def test_feedforward_halves_the_following_error_on_a_trapezoid(plant_file, capsys):
    """``tune --verify model --verify-move trapezoid``: on both axes the
    designed KVFF and KAFF are set, the peak |set-point - position| of the
    one-turn trapezoid is at most half of the same move's without them, and
    the move still ends within 2 % overshoot, settled into +-2 counts, at most
    2 counts off; the design model's prediction of that peak is printed beside it."""
    try:
        rc = cli.main(["--json", "tune", "--all", "--plant-file", str(plant_file), "--settling", "0.35",
                       "--verify", "model", "--verify-move", "trapezoid", "--verify-s", str(VERIFY_S)])
    except SystemExit as e:
        rc = e.code
    cap = capsys.readouterr()
    assert rc == 0, cap.err
    out = json.loads(cap.out)
    assert out["verify"]["faults"] == [] and out["verify"]["move"] == "trapezoid"
    for name in ("x", "z"):
        ax, meas = out["axes"][name], out["verify"][name]
        on = meas["peak_following_error_counts"]
        off = meas["without_feedforward"]["peak_following_error_counts"]
        pred = ax["predicted_trapezoid"]
        print(f"{name}: KVFF_Q16 {ax['settings']['KVFF_Q16']}, KAFF_Q16 {ax['settings']['KAFF_Q16']}, trapezoid "
              f"{ax['verify_trapezoid']}: peak following error {on:.0f} counts with the feed-forward, {off:.0f} "
              f"without (predicted {pred['peak_following_error_counts']:.0f} and "
              f"{pred['peak_following_error_without_feedforward_counts']:.0f}); overshoot {meas['overshoot_pct']:.2f} %, "
              f"+-2 counts at {meas['settling_time_2_counts_s']} s, error {meas['steady_state_error_counts']:.1f}")
        assert ax["settings"]["KVFF_Q16"] > 0 and ax["settings"]["KAFF_Q16"] > 0
        assert on <= MAX_SHARE * off
        assert pred["peak_following_error_counts"] <= MAX_SHARE * pred["peak_following_error_without_feedforward_counts"]
        assert meas["overshoot_pct"] <= MAX_OVERSHOOT_PCT
        assert meas["settling_time_2_counts_s"] is not None and meas["settling_time_2_counts_s"] < VERIFY_S
        assert abs(meas["steady_state_error_counts"]) <= MAX_ERROR_COUNTS


def test_feedforward_leaves_a_step_move_bit_for_bit(plant_file):
    """The feed-forward acts on the profile's speed and acceleration only: on the
    paper's step (no profile) the tuned settings with KVFF and KAFF give the same
    commands and positions, sample for sample, as without them, so the step metrics
    tests/test_tune.py holds are the feed-forward's too."""
    ident = tomllib.loads(plant_file.read_text())["identifiable"]
    ts = [tune_axis(a, ident[n], Wish(settling_s=0.35), 20_000, "test") for a, n in enumerate(("x", "z"))]
    spec = PlantSpec.from_file(plant_file)
    with_ff = tuneverify.config(ts, spec, 0.3)
    assert all(t["KVFF_Q16"] > 0 and t["KAFF_Q16"] > 0 for t in with_ff.tuned)
    a = experiment.run_fast(with_ff)
    b = experiment.run_fast(tuneverify.config(ts, spec, 0.3, feedforward=False))
    assert np.array_equal(a.traj.cmd, b.traj.cmd) and np.array_equal(a.traj.pos, b.traj.pos)
    assert np.abs(a.traj.cmd).max() > 0          # the step did drive


def test_the_fast_path_trapezoid_is_the_firmwares_profile(plant_file):
    """The verification's trapezoid on the fast path follows the firmware's
    profile (the oracle's, bit for bit the C): the set-point the error is taken
    from rises at AMAX, cruises at VMAX and lands on the target."""
    ident = tomllib.loads(plant_file.read_text())["identifiable"]
    t = tune_axis(0, ident["x"], Wish(settling_s=0.35), 20_000, "test")
    cfg = tuneverify.config([t], PlantSpec.from_file(plant_file), 1.6, "trapezoid")
    run = experiment.run_fast(cfg)
    sp = (run.traj.err[:, 0] + run.traj.pos[:, 0]) / tuneverify.RAD_PER_COUNT     # set-point, counts
    vmax, amax = t.trapezoid
    v = np.diff(sp) / (cfg.period_us * 1e-6)
    assert sp[0] < 10 and sp[-1] == cfg.target_counts
    assert v.max() == pytest.approx(vmax, abs=1000)          # one count per 1 ms sample of rounding
    t_top = np.argmax(v > 0.9 * vmax) * cfg.period_us * 1e-6  # it ramps at AMAX, it does not jump
    assert t_top == pytest.approx(0.9 * vmax / amax, abs=0.01)
