# SPDX-License-Identifier: MIT
"""docs/hardware.md's bring-up, in its order, on the simulated board, as a
user does it: the ``torqueloop`` command against a board in another process
(``torqueloop sim``, its configuration flash in a file, its limit switches at
+-20000 counts), one step after the other on the same board, each step's
outcome checked the way the user reads it:

  1. wiring: the board answers (``info``), nothing is faulted or enabled and
     no limit switch reads open in mid-travel (``status``);
  2. open-loop drive both ways, the encoder sign read from what it printed
     (``drive 5%``, ``drive -5%``), the axis disabled afterwards;
  3. homing to the negative switch, enabling the axis itself;
  4. parameters set in physical units (a travel limit, a speed, a gain);
  5. ``save``;
  6. a power cycle: the board process ends and a new one starts on the same
     flash file;
  7. the parameters are back and ``status`` says they are the saved ones;
  8. homing again (the position does not survive a power cycle) and a
     closed-loop move that reaches its target, settled, exit 0, no fault.
"""

from __future__ import annotations

import os
import subprocess
import sys
import time

import pytest

from simproc import run_cli, sim_board
from torqueloop.host import serve as hserve

SWITCHES = 20_000              # counts from the start position to each switch
COUNTS_PER_MM = 2100           # 8400 counts per turn of a 4 mm lead screw


@pytest.fixture
def user(tmp_path, monkeypatch) -> dict[str, str]:
    """A user's environment: a key made with `key new`, named by $TORQUELOOP_KEY_FILE."""
    key = tmp_path / "config" / "torqueloop" / "lab.key"
    env = dict(os.environ, TORQUELOOP_KEY_FILE=str(key), TORQUELOOP_STATE_DIR=str(tmp_path / "state"))
    env.pop(hserve.SERVER_ENV, None)
    r = subprocess.run([sys.executable, "-m", "torqueloop.cli", "key", "new", str(key)], env=env,
                       capture_output=True, text=True, timeout=60)
    assert r.returncode == 0, r.stderr
    for k in ("TORQUELOOP_KEY_FILE", "TORQUELOOP_STATE_DIR"):
        monkeypatch.setenv(k, env[k])
    monkeypatch.delenv(hserve.SERVER_ENV, raising=False)
    return env


def tl(url: str, capsys, *args: str, rc: int = 0) -> dict:
    """One command as the user types it (with --json); its last JSON line."""
    return run_cli(url, capsys, *args, rc=rc)[0]


def board(env: dict[str, str], flash) -> object:
    return sim_board("sim", "--port", "0", "--switches", str(SWITCHES), "--flash", str(flash), env=env)


def test_the_documented_bring_up_in_order(user, tmp_path, capsys) -> None:
    flash = tmp_path / "epcs64.bin"
    t0 = time.monotonic()
    with board(user, flash) as url:
        # 1. wiring: the link answers; no fault, nothing enabled, no switch open in mid-travel
        info = tl(url, capsys, "info")
        assert info["axis_count"] == 2
        st = {**tl(url, capsys, "status", "--axis", "0"), **tl(url, capsys, "status", "--axis", "1")}
        for ax in ("0", "1"):
            assert st[ax]["fault_names"] == [] and not st[ax]["enabled"] and st[ax]["limits"] == 0, st[ax]
        assert st["0"]["saved_parameters"]["saved"] is False          # a new board: nothing saved yet

        # 2. open-loop drive both ways: the encoder counts the way the duty says
        up = tl(url, capsys, "drive", "5%", "--for", "2")
        down = tl(url, capsys, "drive", "-5%", "--for", "2")
        assert up["sign_matches"] and down["sign_matches"], (up, down)
        # a few hundred counts a second once it runs; a board that falls behind on a loaded machine
        # starts later - far more than the few counts a disabled axis creeps
        assert up["moved_counts"] > 50 and down["moved_counts"] < -50, (up["moved_counts"], down["moved_counts"])
        assert not up["faults"] and not down["faults"]
        st = tl(url, capsys, "status", "--axis", "0")
        assert not st["0"]["enabled"] and st["0"]["fault_names"] == []

        # 3. home to the negative switch; homing enables the axis itself and ends disabled
        tl(url, capsys, "set", "home_vel", "5mm/s")
        home = tl(url, capsys, "home", "neg", "--wait", "30")
        assert home["home_state"] == "homed" and home["faults"] == [] and home["enabled"] is False, home

        # 4. parameters in physical units
        assert tl(url, capsys, "set", "soft_max", "15mm")["raw"] == 15 * COUNTS_PER_MM
        assert tl(url, capsys, "set", "vmax", "8mm/s")["raw"] == 8 * COUNTS_PER_MM
        kp = tl(url, capsys, "get", "kp", "--axis", "0")["kp"]["value"]
        tl(url, capsys, "set", "kp", f"{kp * 1.25:.4f}", "--axis", "0")
        kp_set = tl(url, capsys, "get", "kp", "--axis", "0")["kp"]["value"]
        assert abs(kp_set - kp * 1.25) < 1e-3 * max(1.0, kp)

        # 5. save
        saved = tl(url, capsys, "save")
        assert saved["saved"] is True and saved["differs"] is False, saved
    assert flash.stat().st_size > 0, "the save reached the flash file"

    # 6. power cycle: a new board process on the same flash
    with board(user, flash) as url:
        # 7. the parameters are back, and status says they are the saved ones
        st = tl(url, capsys, "status", "--axis", "0")
        assert st["0"]["saved_parameters"] == {"saved": True, "differs": False, "seq": saved["seq"]}, st["0"]
        assert tl(url, capsys, "get", "soft_max", "--axis", "0")["soft_max"]["raw"] == 15 * COUNTS_PER_MM
        assert tl(url, capsys, "get", "vmax", "--axis", "0")["vmax"]["raw"] == 8 * COUNTS_PER_MM
        assert abs(tl(url, capsys, "get", "kp", "--axis", "0")["kp"]["value"] - kp_set) < 1e-6

        # 8. home again (the position is lost at power-off), then a closed-loop move
        assert st["0"]["home_state"] != "homed"
        home = tl(url, capsys, "home", "neg", "--wait", "30")
        assert home["home_state"] == "homed" and home["faults"] == [], home
        moved = tl(url, capsys, "move", "5mm", "--enable", "--wait", "20", "--tolerance", "40")
        assert moved["settled"] is True and abs(moved["error_counts"]) <= 40 and moved["disabled"] is True, moved
        st = tl(url, capsys, "status", "--axis", "0")
        assert st["0"]["fault_names"] == [] and not st["0"]["enabled"], st["0"]
        assert abs(st["0"]["position"] - 5 * COUNTS_PER_MM) <= 100, st["0"]
    print(f"bring-up in order: drive 5% {up['moved_counts']:+d} counts, -5% {down['moved_counts']:+d}; "
          f"saved copy {saved['seq']} back after the power cycle; move 5 mm settled "
          f"{moved['error_counts']:+d} counts off; {time.monotonic() - t0:.1f} s")
