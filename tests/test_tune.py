# SPDX-License-Identifier: MIT
"""``torqueloop tune``: gains from a plant file, checked in the closed loop.

The plant is lab-2025 with its rotor friction scaled by 1.25 and its rotor
inertia by 0.8 (as tests/test_identify.py scales it), exported as a plant
file whose ``[identifiable.<axis>]`` keys the design reads.  ``--verify
model`` runs the tuned one-turn step on the fast path (the firmware's law
bit for bit, the PWM block's events, the plant's stepper): what it measures
is held against what the design predicted, within the tolerance the design
model is stated to (docs/identification.md, "Tuning"): overshoot within 1
point, the 2 % settling time within 15 %, the steady-state error (the mean
of the record's last 10 %, the same record in both) within 3 counts.  ``--apply`` is run against the simulated board (the firmware's C)."""

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


def test_the_fast_model_measures_what_the_design_predicted(plant_file, capsys):
    rc, cap = _run(capsys, ["--json", "tune", "-a", "0", "--plant-file", str(plant_file), "--settling", "0.3",
                            "--verify", "model", "--verify-s", "1.5"])
    assert rc == 0, cap.err
    out = json.loads(cap.out)
    x = out["axes"]["x"]
    pred, meas = x["predicted"], out["verify"]["x"]
    print(f"x: {x['settings']}, gm {x['gain_margin_db']:.1f} dB, pm {x['phase_margin_deg']:.0f} deg")
    for k in ("overshoot_pct", "settling_time_s", "steady_state_error_counts"):
        print(f"  {k}: predicted {pred[k]}, fast model {meas[k]}")
    assert x["gain_margin_db"] >= 6 and x["phase_margin_deg"] >= 30
    assert x["carrier_hz"] >= 20_000 and x["settings"]["PW0"] > 0 and x["settings"]["LAW"] == 3
    assert out["verify"]["faults"] == []
    assert abs(meas["overshoot_pct"] - pred["overshoot_pct"]) <= 1.0
    assert meas["settling_time_s"] is not None and pred["settling_time_s"] is not None
    assert meas["settling_time_s"] == pytest.approx(pred["settling_time_s"], rel=0.15)
    assert abs(meas["steady_state_error_counts"] - pred["steady_state_error_counts"]) <= 3.0


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
        (["tune", "--plant-file", str(plant_file), "--settling", "0.2"], "beyond what the board holds"),
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
