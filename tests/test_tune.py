# SPDX-License-Identifier: MIT
"""``torqueloop tune``: gains from a plant file, checked in the closed loop.

The plant is lab-2025 with its rotor friction scaled by 1.25 and its rotor
inertia by 0.8 (as tests/test_identify.py scales it), exported as a plant
file whose ``[identifiable.<axis>]`` keys the design reads.  ``--verify
model`` runs the tuned one-turn step on the fast path (the firmware's law
bit for bit, the PWM block's events, the plant's stepper): what it measures
is held to the issue's target (settled into +-2 counts with at most 2 %
overshoot and 2 counts of error, at least twice as fast as the Table 1
gains on the same plant) and against what the design predicted, within the
tolerance the design model is stated to (docs/identification.md, "Tuning").  ``--apply`` is run against the simulated board (the firmware's C)."""

import json

import pytest

from sim_models.variants import PlantSpec
from scaled_plant import scaled_lab_2025
from torqueloop import cli
from torqueloop.host.client import Client
from torqueloop.sim.simboard import SimBoard, SimBoardTransport
from torqueloop.spec import auth



@pytest.fixture(scope="module")
def plant_file(tmp_path_factory):
    return scaled_lab_2025(tmp_path_factory.mktemp("plant"))[1]


def _run(capsys, args, client=None):
    try:
        rc = cli.main(args, client=client)
    except SystemExit as e:      # argparse's usage error
        rc = e.code
    return rc, capsys.readouterr()


#: the issue's target for the tuned PID on the scaled plant (both axes, a one-turn step)
MAX_OVERSHOOT_PCT, TIGHT_COUNTS, MAX_ERROR_COUNTS, MIN_CARRIER_HZ, FASTER = 2.0, 2.0, 2.0, 20_000, 2.0
#: the wish the tuning is asked (the design picks damping and integral pole for it)
SETTLING_WISH_S, VERIFY_S = "0.35", 3.0


def test_the_tuned_pid_settles_into_two_counts_twice_as_fast_as_table1(plant_file, capsys):
    """On the fast model (the firmware's law bit for bit, the PWM block's
    events, the plant's stepper) the tuned PID with its compensation, at a
    carrier of 20 kHz or more, settles the one-turn step into +-2 counts with
    at most 2 % overshoot and at most 2 counts of steady-state error on both
    axes; the Table 1 gains on the same plant (--table1-s, twice the slower
    axis's settling) are not settled into +-2 counts within twice that time.
    The measurement is also held to the design's prediction: overshoot within
    1 point, the 2 % settling within 15 %."""
    table1_s = FASTER * VERIFY_S          # long enough to tell "twice as slow" for any settling within VERIFY_S
    rc, cap = _run(capsys, ["--json", "tune", "--all", "--plant-file", str(plant_file), "--settling", SETTLING_WISH_S,
                            "--verify", "model", "--verify-s", str(VERIFY_S), "--table1-s", str(table1_s)])
    assert rc == 0, cap.err
    out = json.loads(cap.out)
    assert out["verify"]["faults"] == []
    for name in ("x", "z"):
        ax, meas = out["axes"][name], out["verify"][name]
        pred, t1 = ax["predicted"], meas["table1"]
        print(f"{name}: {ax['settings']}, zeta {ax['zeta']:.2f}, integral pole {ax['pid_pole_alpha']} wn, "
              f"gm {ax['gain_margin_db']:.1f} dB, pm {ax['phase_margin_deg']:.0f} deg")
        for k in ("overshoot_pct", "settling_time_s", "settling_time_2_counts_s", "steady_state_error_counts"):
            print(f"  {k}: predicted {pred[k]}, fast model {meas[k]}, Table 1 {t1[k]}")
        assert ax["gain_margin_db"] >= 6 and ax["phase_margin_deg"] >= 30
        assert ax["carrier_hz"] >= MIN_CARRIER_HZ and ax["settings"]["PW0"] > 0 and ax["settings"]["LAW"] == 3
        assert ax["settings"]["IZONE_Q16"] > 0
        assert meas["overshoot_pct"] <= MAX_OVERSHOOT_PCT
        tight = meas["settling_time_2_counts_s"]
        assert tight is not None and tight < VERIFY_S
        assert abs(meas["steady_state_error_counts"]) <= MAX_ERROR_COUNTS
        assert meas["max_abs_error_last_10pct_counts"] <= TIGHT_COUNTS
        assert t1["settling_time_2_counts_s"] is None or t1["settling_time_2_counts_s"] >= FASTER * tight
        assert abs(meas["overshoot_pct"] - pred["overshoot_pct"]) <= 1.0
        assert meas["settling_time_s"] == pytest.approx(pred["settling_time_s"], rel=0.15)


def test_tune_refuses_bad_input_in_one_line(plant_file, tmp_path, capsys):
    broken = tmp_path / "broken.toml"
    broken.write_text(plant_file.read_text().replace("speed_gain_rad_per_s_per_v =", "speed_gain_typo ="))
    cases = [
        (["tune", "--plant-file", str(tmp_path / "none.toml")], "cannot read"),
        (["tune", "--plant-file", str(plant_file), "--save"], "--apply"),
        (["tune", "--plant-file", str(plant_file), "--settling", "0.3", "--bandwidth", "2"], "not both"),
        (["tune", "--plant-file", str(broken)], "speed_gain_rad_per_s_per_v missing"),
        (["tune", "--plant-file", str(plant_file), "--pwm-freq", "90000"], "--pwm-freq"),
        (["tune", "--plant-file", str(plant_file), "--law", "p"], "invalid choice"),
        (["tune", "--plant-file", str(plant_file), "--min-pm", "89"], "phase"),
        (["tune", "--plant-file", str(plant_file), "--settling", "0.05"], "beyond what the board holds"),
    ]
    for args, what in cases:
        rc, cap = _run(capsys, args)
        err = cap.err.strip().splitlines()
        assert rc in (1, 2), (args, rc)
        assert len(err) == 1 and "Traceback" not in err[0] and what in err[0], (args, err)


def _board(plant_file):
    b = SimBoard(key=auth.TEST_KEY, plant=PlantSpec.from_file(plant_file))
    c = Client(SimBoardTransport(b), timeout=1.0, retries=0, clock=lambda: b.t, key=auth.TEST_KEY)
    c.connect()
    return b, c


def test_apply_writes_the_gains_and_saves_them(plant_file, tmp_path, monkeypatch, capsys):
    key = tmp_path / "link.key"
    auth.write_key_file(key, auth.TEST_KEY)
    monkeypatch.setenv(auth.KEY_FILE_ENV, str(key))
    b, c = _board(plant_file)
    rc, cap = _run(capsys, ["--json", "tune", "--all", "--plant-file", str(plant_file), "--apply", "--save"], c)
    assert rc == 0, cap.err
    out = json.loads(cap.out)
    for ax, name in ((0, "x"), (1, "z")):
        want = out["axes"][name]["settings"]
        assert {k: c.get_param(k, ax) for k in want} == want
    assert c.get_param("PERIOD_US") == 1000
    assert out["applied"]["store"]["differs"] == 0
    # refused while the axis moves: one line, nothing written
    c.enable(1, True)
    c.move(0, 8400, unhomed=True)
    c.pump(0.05)
    kp = c.get_param("KP_Q16", 0)
    rc, cap = _run(capsys, ["tune", "-a", "0", "--plant-file", str(plant_file), "--settling", "0.3", "--apply"], c)
    err = cap.err.strip().splitlines()
    assert rc == 1 and len(err) == 1 and "moving" in err[0], err
    assert c.get_param("KP_Q16", 0) == kp
