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


def sweep(tmp_path, capsys, plant: str, *args: str) -> tuple[dict, dict, dict]:
    key = tmp_path / "link.key"
    auth.write_key_file(key, auth.new_key())
    env = dict(os.environ, **{auth.KEY_FILE_ENV: str(key)})
    out = tmp_path / "sweep.json"
    with sim_board("sim", "--port", "0", "--plant", plant, env=env) as url:
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


def test_the_lab_plant_s_dead_zone_is_found_in_both_directions(tmp_path, capsys) -> None:
    step = 0.5
    # lab-2025: the hard brush drop the closed form above assumes (lab's brushes are ohmic below a knee)
    res, _, _ = sweep(tmp_path, capsys, "lab-2025", "--carriers", "450", "--start", "2", "--step", str(step),
                      "--max", "9")
    want = breakaway_percent("lab-2025")
    ramps = res["ramps"]
    print("lab-2025 plant, 450 Hz: expected breakaway %.2f %%; found %s" % (
        want, [(r["direction"], r["breakaway_percent"], r["stop_percent"]) for r in ramps]))
    assert [r["direction"] for r in ramps] == [1, -1]
    for r in ramps:
        assert not r["fault"] and abs(r["carrier_hz"] - 448.4) < 0.5
        assert want - step <= r["breakaway_percent"] <= want + 2 * step, r
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
