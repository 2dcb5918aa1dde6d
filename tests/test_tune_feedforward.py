# SPDX-License-Identifier: MIT
"""``torqueloop tune``'s velocity and acceleration feed-forward (KVFF_Q16,
KAFF_Q16), designed from the plant file's identifiable keys and checked on a
trapezoid move on the fast model (the firmware's law bit for bit, the PWM
block's events, the plant's stepper).

The plant is tests/test_tune.py's: lab-2025 with its rotor friction scaled
by 1.25 and its inertia by 0.8, which the design only sees through the plant
file's identifiable keys."""

import dataclasses
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


def test_the_dither_and_the_feedforward_reach_the_fast_paths_law(plant_file):
    """ExperimentConfig's tuned fields carry DITHER_AMP, DITHER_HALF, KAFF_Q16, VMAX
    and AMAX to the firmware's law on the fast path (as ``configure`` writes them to
    the board): on a 20-count step (commands inside the limit, the error outside
    the hunting guard's zone) a 300-step dither of half-period 1 moves the command
    by about 600 steps the other way every sample; on the trapezoid's first
    samples KAFF_Q16 adds KAFF AMAX steps."""
    ident = tomllib.loads(plant_file.read_text())["identifiable"]
    ts = [tune_axis(a, ident[n], Wish(settling_s=0.35), 20_000, "test") for a, n in enumerate(("x", "z"))]
    spec = PlantSpec.from_file(plant_file)
    step = dataclasses.replace(tuneverify.config(ts, spec, 0.01), step_rad=20 * tuneverify.RAD_PER_COUNT)
    dith = dataclasses.replace(step, tuned=tuple(t | {"DITHER_AMP": 300, "DITHER_HALF": 1} for t in step.tuned))
    a, b = (experiment.run_fast(cfg).traj.cmd[:, 0] for cfg in (step, dith))
    assert step.target_counts == 20 and np.abs(a).max() < 1023 - 300
    d = np.diff(b)
    print(f"dithered command's changes: {d.tolist()}")
    assert np.all(np.sign(d[1:]) == -np.sign(d[:-1])) and np.median(np.abs(d)) == pytest.approx(600, abs=60)
    trap = tuneverify.config(ts, spec, 0.05, "trapezoid")
    assert trap.profile(0) == ts[0].trapezoid and trap.profile(1) == ts[1].trapezoid
    no_aff = dataclasses.replace(trap, tuned=tuple(t | {"KAFF_Q16": 0} for t in trap.tuned))
    a, c = (experiment.run_fast(cfg).traj.cmd[1:, 0] for cfg in (trap, no_aff))
    kaff = ts[0].design.kaff * ts[0].trapezoid[1]          # steps the acceleration feed-forward adds
    print(f"KAFF AMAX {kaff:.0f} steps; the command's difference: {(a - c).tolist()}")
    # until the plants' motions part (a few samples): exactly the feed-forward, within its rounding
    assert np.all(np.abs((a - c)[:4] - kaff) <= 1)


def test_a_trapezoid_without_a_verification_is_refused_in_one_line(plant_file, capsys):
    try:
        rc = cli.main(["tune", "-a", "0", "--plant-file", str(plant_file), "--verify-move", "trapezoid"])
    except SystemExit as e:
        rc = e.code
    err = capsys.readouterr().err
    assert rc != 0 and "--verify-move" in err and len(err.strip().splitlines()) == 1 and "Traceback" not in err
