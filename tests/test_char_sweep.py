# SPDX-License-Identifier: MIT
"""The board as the characterisation's PWM source, encoder-only
(``torqueloop characterize sweep``, torqueloop/host/sweep.py): against
``torqueloop sim`` in its own process, over TCP, as a user runs it.

Variant against variant: on the ``lab`` plant (motor-side stiction and brush
drop) the breakaway duty found with the open-loop drive and the encoder is
where the plant's parameters put it - the duty whose current in the on-time,
(V - brush drop) / R, gives the breakaway torque T_s (docs/plant.md) - in
both directions, and the motor stops again below it; on the ``paper`` plant,
which has no motor-side dead zone, it moves at the first duty tried.  The
axis's carrier is restored and the axis disabled afterwards.
"""

from __future__ import annotations

import json
import os

import pytest

from simproc import sim_board
from torqueloop import cli
from torqueloop.spec import auth


def breakaway_percent(plant: str) -> float:
    """The duty whose on-time current (V - brush drop) / R makes the breakaway torque of axis 0."""
    from sim_models.variants import plant_of

    p = plant_of(plant).params()
    a = p.axes[0]
    return 100 * a.motor_static_N_m * a.resistance_ohm / (a.ke_V_s_per_rad * (p.bridge.supply_V - a.brush_drop_V))


def sweep(tmp_path, capsys, plant: str, *args: str, speed: float = 1.0) -> tuple[dict, dict, dict]:
    key = tmp_path / "link.key"
    auth.write_key_file(key, auth.new_key())
    env = dict(os.environ, **{auth.KEY_FILE_ENV: str(key)})
    out = tmp_path / "sweep.json"
    with sim_board("sim", "--port", "0", "--plant", plant, "--speed", str(speed), env=env) as url:
        base = ["-u", url, "-k", str(key), "--json"]
        capsys.readouterr()
        assert cli.main([*base, "get", "pwm_freq"]) == 0
        before = json.loads(capsys.readouterr().out)
        rc = cli.main([*base, "characterize", "sweep", "--out", str(out), *args])
        res = json.loads(capsys.readouterr().out)
        assert rc == 0, res
        assert cli.main([*base, "get", "pwm_freq"]) == 0
        after = json.loads(capsys.readouterr().out)
        assert cli.main([*base, "status"]) == 0
        st = json.loads(capsys.readouterr().out)
    assert after == before, "the carrier is restored"
    assert st["0"]["enabled"] == 0 and st["0"]["faults"] == 0
    assert json.loads(out.read_text()) == res
    return res, before, st


# speed 0.4: the board lives 0.4 s per second of the host's; the holds are the board's time
# (its telemetry's clock), so the same dead zone is found as on a board in real time.  With holds
# counted in host time the board held each duty 0.4 of the hold and read high
@pytest.mark.parametrize("speed", [1.0, 0.4])
def test_the_lab_plant_s_dead_zone_is_found_in_both_directions(tmp_path, capsys, speed: float) -> None:
    step = 0.5
    # lab-2025: the hard brush drop the closed form above assumes (lab's brushes are ohmic below a knee)
    res, _, _ = sweep(tmp_path, capsys, "lab-2025", "--carriers", "450", "--start", "2", "--step", str(step),
                      "--max", "9", speed=speed)
    want = breakaway_percent("lab-2025")
    ramps = res["ramps"]
    print("lab-2025 plant, 450 Hz, board at %g x real time: expected breakaway %.2f %%; found %s" % (
        speed, want, [(r["direction"], r["breakaway_percent"], r["stop_percent"]) for r in ramps]))
    assert [r["direction"] for r in ramps] == [1, -1]
    for r in ramps:
        assert not r["fault"] and abs(r["carrier_hz"] - 448.4) < 0.5
        assert want - step <= r["breakaway_percent"] <= want + step, r   # the first step above it, or one below (ripple)
        assert r["stop_percent"] is not None and r["stop_percent"] < r["breakaway_percent"], r
        # on the way up it did not move before the breakaway
        up = r["points"][:[d for d, _ in r["points"]].index(r["breakaway_percent"])]
        assert up and all(abs(m) < 3 for _, m in up), r["points"]


def test_the_paper_plant_has_no_dead_zone_to_find(tmp_path, capsys) -> None:
    res, _, _ = sweep(tmp_path, capsys, "paper", "--start", "1", "--step", "1", "--max", "5")
    assert {r["breakaway_percent"] for r in res["ramps"]} == {1.0}, res["ramps"]


@pytest.mark.parametrize("args,msg", [(["--carriers", "fast"], "comma-separated"),
                                      (["--carriers", "0"], "above 0 Hz"),
                                      (["--step", "0"], "outside")])
def test_bad_sweep_arguments_are_one_line(args, msg, capsys) -> None:
    try:
        rc = cli.main(["-u", "socket://127.0.0.1:1", "characterize", "sweep", *args])
    except SystemExit as e:
        rc = e.code
    err = capsys.readouterr().err
    assert rc == 2 and msg in err and len(err.strip().splitlines()) == 1, err


# ---- with a force gauge: the method's own sweeps, the board as the PWM source ----------------

def gauge_readings(path, wheel_r: float) -> None:
    """A lab's readings (sweep,freq_hz,duty_pct,force_n,current_a): a stall torque of
    2.4 N m, at 50 % half of it with a frequency dependence that crosses tau_max / 2 at
    450 Hz (step 5), and a torque line in duty from 11 % (step 7's PW0)."""
    from torqueloop.characterize import board

    rows = ["sweep,freq_hz,duty_pct,force_n,current_a", f"stall,,100,{2.4 / wheel_r:.4f},2.18"]
    for f in board.PAPER_FREQS_HZ:
        t = 2.4 / 2 * (1 + 0.3 * (450.0 - f) / 450.0)
        rows.append(f"frequency,{f:g},50,{t / wheel_r:.4f},{t / 1.1:.4f}")
    for d in board.DUTY_PCTS:
        rows.append(f"duty,,{d:g},{max(0.0, 2.4 * (d - 11.0) / 89.0) / wheel_r:.4f},{0.02 * d:.4f}")
    path.write_text("\n".join(rows) + "\n")


def test_the_gauge_sweep_holds_the_method_s_settings_and_gives_the_configuration(tmp_path, capsys) -> None:
    from torqueloop.characterize import load_config, read_sweep

    key = tmp_path / "link.key"
    auth.write_key_file(key, auth.new_key())
    env = dict(os.environ, **{auth.KEY_FILE_ENV: str(key)})
    readings, out_dir, cfg = tmp_path / "readings.csv", tmp_path / "data", tmp_path / "cfg.json"
    gauge_readings(readings, 0.02)
    with sim_board("sim", "--port", "0", env=env) as url:
        base = ["-u", url, "-k", str(key), "--json"]
        capsys.readouterr()
        assert cli.main([*base, "get", "pwm_freq"]) == 0
        before = json.loads(capsys.readouterr().out)
        rc = cli.main([*base, "characterize", "sweep", "--gauge", str(out_dir), "--readings", str(readings),
                       "--wheel-radius", "0.02", "--settle", "0.1", "--config", str(cfg)])
        out = capsys.readouterr().out
        res = json.loads(out.strip().splitlines()[-1])
        assert rc == 0, out
        assert cli.main([*base, "get", "pwm_freq"]) == 0
        after = json.loads(capsys.readouterr().out)
        assert cli.main([*base, "status", "--axis", "0"]) == 0
        st = json.loads(capsys.readouterr().out)
    print("gauge sweep:", res)
    # step 5's crossing of tau_max / 2, interpolated between the board's carriers (450 Hz by construction)
    assert res["status"] == "pass" and abs(res["chosen_hz"] - 450) < 5, res
    fs = read_sweep(out_dir / "x" / "freq_sweep.csv")
    # every carrier as the board made it (eq. 4), not as asked
    assert len(fs.x) == 19 and abs(fs.x[-1] - 498.7) < 0.5 and abs(fs.stall_torque_nm - 2.4) < 1e-3
    ds = [read_sweep(p) for p in sorted((out_dir / "x").glob("duty_sweep_*hz.csv"))]
    assert [round(s.freq_hz, 1) for s in ds] == [448.4] and len(ds[0].x) == 34
    x = load_config(cfg).axes["x"]
    assert x.count_max == 109 and abs(x.pw0_counts - 113) <= 2, x
    assert after == before and st["0"]["enabled"] == 0 and st["0"]["faults"] == 0


def test_the_gauge_reading_prompt_feeds_the_watchdog_and_asks_again(tmp_path) -> None:
    import io

    from torqueloop.characterize import board

    r, w = os.pipe()
    os.write(w, b"48.5\n-1 2\n48.5, 1.2\n")
    os.close(w)
    fed, out = [], io.StringIO()
    with os.fdopen(r) as inp:
        got = board.prompt_reader(inp, out)("duty", 448.4, 30.0, lambda: fed.append(1))
        assert got == (48.5, 1.2)
        text = out.getvalue()
        assert text.count("duty 30 % at 448.4 Hz: force N and current A?") == 3
        assert "two numbers" in text and "negative" in text
        with pytest.raises(board.ReadingError, match="end of input"):
            board.prompt_reader(inp, out)("duty", 448.4, 33.0, lambda: None)


def test_gauge_sweep_arguments_are_one_line(tmp_path, capsys) -> None:
    key = tmp_path / "k.key"
    auth.write_key_file(key, auth.new_key())
    for args, msg in ((["--gauge", str(tmp_path)], "--wheel-radius"),
                      (["--gauge", str(tmp_path), "--wheel-radius", "0.02", "--freqs", "50,40,30,20"], "increasing"),
                      (["--gauge", str(tmp_path), "--wheel-radius", "0.02", "--readings", str(tmp_path / "no.csv")],
                       "no.csv")):
        try:
            rc = cli.main(["-u", "socket://127.0.0.1:1", "-k", str(key), "characterize", "sweep", *args])
        except SystemExit as e:
            rc = e.code
        err = capsys.readouterr().err
        assert rc in (1, 2) and msg in err and len(err.strip().splitlines()) == 1 and "Traceback" not in err, err
