# SPDX-License-Identifier: MIT
"""The bring-up a new user does, against the simulated board, in order, with
the ``torqueloop`` command: a key in a folder that does not exist yet, info,
homing to a limit switch with ``--enable``, a move with ``--wait`` that says
"settled", exits 0 and leaves no fault behind (the link watchdog never
trips); ``monitor`` in one process while ``move`` runs from another through
``torqueloop serve``; and ``torqueloop shell`` driven through a
pseudo-terminal (pexpect) with its live plot written to a frame file.

The simulated board runs with its limit switches at +-20000 counts
(``sim --switches``), so homing at 5 mm/s takes seconds, not minutes.
"""

from __future__ import annotations

import json
import os
import signal
import stat
import subprocess
import sys
import time
from pathlib import Path

import pytest

from simproc import run_cli as tl
from simproc import sim_board
from torqueloop import cli
from torqueloop.flow import terminal
from torqueloop.host import serve as hserve

SWITCHES = 20_000


@pytest.fixture(scope="module")
def env(tmp_path_factory) -> dict[str, str]:
    """A user's environment: the key made with `key new` in a folder that does not exist yet,
    named by $TORQUELOOP_KEY_FILE; servers' state files in a folder of this test's own."""
    d = tmp_path_factory.mktemp("user")
    key = d / "config" / "torqueloop" / "lab.key"
    e = dict(os.environ, TORQUELOOP_KEY_FILE=str(key), TORQUELOOP_STATE_DIR=str(d / "state"))
    e.pop("DISPLAY", None)
    e.pop("WAYLAND_DISPLAY", None)
    e.pop(hserve.SERVER_ENV, None)
    r = subprocess.run([sys.executable, "-m", "torqueloop.cli", "key", "new", str(key)], env=e,
                       capture_output=True, text=True, timeout=60)
    assert r.returncode == 0, r.stderr
    assert stat.S_IMODE(key.parent.stat().st_mode) == 0o700 and stat.S_IMODE(key.stat().st_mode) == 0o600
    return e


@pytest.fixture(scope="module")
def url(env):
    with sim_board("sim", "--port", "0", "--switches", str(SWITCHES), env=env) as u:
        yield u


@pytest.fixture
def user_env(env, monkeypatch):
    for k in ("TORQUELOOP_KEY_FILE", "TORQUELOOP_STATE_DIR"):
        monkeypatch.setenv(k, env[k])
    monkeypatch.delenv(hserve.SERVER_ENV, raising=False)
    return env


def test_bring_up_as_a_user_would(url, user_env, capsys) -> None:
    capsys.readouterr()
    with pytest.raises(SystemExit) as e:
        cli.main(["--version"])
    assert e.value.code == 0 and capsys.readouterr().out.startswith("torqueloop ")

    info, _ = tl(url, capsys, "info")
    assert info["axis_count"] == 2
    st, _ = tl(url, capsys, "status")
    # the keys scripts read from `--json status`
    assert {"position", "setpoint", "velocity_q8", "pwm_cmd", "enabled", "moving", "home", "home_state",
            "limits", "faults", "fault_names", "rx_errors"} <= set(st["0"])

    # homing moves the soft-limit window, so it starts with every axis disabled, and a switch
    # homing enables its axis itself: no `enable` first (which the link watchdog would undo)
    got, _ = tl(url, capsys, "set", "home_vel", "5mm/s")
    assert got["raw"] == 10_500                          # 5 mm/s at a 4 mm lead, 8400 counts per turn
    home, _ = tl(url, capsys, "home", "neg", "--wait", "30")
    assert home["home_state"] == "homed" and home["faults"] == [] and home["enabled"] is False

    moved, _ = tl(url, capsys, "move", "2mm", "--enable", "--wait", "15", "--tolerance", "40")
    assert moved["settled"] is True and abs(moved["error_counts"]) <= 40 and moved["disabled"] is True
    # a negative target with a unit is a target, not an option
    before, _ = tl(url, capsys, "status")
    back, _ = tl(url, capsys, "move", "-1mm", "--relative", "--enable", "--wait", "15", "--tolerance", "40")
    # 1 mm (2100 counts) below where it stood: a disabled axis may still creep some tens of counts (the
    # screw's elastic pre-sliding relaxing), so "where it stood" is known to that much, far from 0 or +2100
    assert back["settled"] is True
    assert abs(back["target_counts"] - (before["0"]["position"] - 2100)) <= 100, (before["0"], back)
    # longer than the 500 ms link watchdog: nothing trips, since nothing is left enabled
    time.sleep(0.8)
    st, _ = tl(url, capsys, "status")
    assert st["0"]["fault_names"] == [] and not st["0"]["enabled"], st

    # a move that cannot settle in the time given says so and exits 1, and still ends disabled
    short, _ = tl(url, capsys, "move", "6mm", "--enable", "--wait", "0.05", rc=1)
    assert short["settled"] is False
    st, _ = tl(url, capsys, "status")
    assert not st["0"]["enabled"]

    # units one way: limits in mm, the carrier refused when the divider cannot make it
    got, _ = tl(url, capsys, "set", "soft_max", "40mm")
    assert got["raw"] == 84_000
    _, err = tl(url, capsys, "set", "pwm_freq", "20000", rc=2)
    assert "16292 Hz" in err and "24438 Hz" in err and "--nearest" in err
    got, _ = tl(url, capsys, "set", "pwm_freq", "20000", "--nearest")
    assert got["requested"] == 20000 and round(got["value"]) == 16292
    tl(url, capsys, "set", "pwm_freq", "450")
    _, err = tl(url, capsys, "set", "vmax", "5mm", rc=2)
    assert "not a speed" in err


def test_hold_keeps_the_axis_enabled_until_ctrl_c(url, user_env) -> None:
    p = _start(["-u", url, "move", "0.5rev", "--relative", "--unhomed", "--enable", "--wait", "15",
                "--tolerance", "40", "--hold"], user_env)
    try:
        for line in p.stderr:                                # it says when it starts holding
            if "holding axis 0" in line:
                break
        else:
            pytest.fail(f"--hold never held: {p.stdout.read()}")
        # More than twice the 500 ms link watchdog.  The board takes one client, so the check is the
        # holder's own: it ends at once, exit 1, if the axis faults or is disabled while it holds.
        time.sleep(1.2)
        assert p.poll() is None, p.stderr.read()
    finally:
        p.send_signal(signal.SIGINT)
        rc = p.wait(30)
    assert rc == 0
    st = json.loads(subprocess.run([sys.executable, "-m", "torqueloop.cli", "-u", url, "--json", "status"],
                                   env=user_env, capture_output=True, text=True, timeout=60).stdout)["0"]
    assert not st["enabled"] and st["fault_names"] == [], st


@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM], ids=["ctrl-c", "kill"])
def test_a_move_cut_short_disables_the_axis_at_once(url, user_env, sig) -> None:
    """Ctrl-C (or `kill`) while `move --wait` waits: the axis is disabled there
    and then, one line says so, exit 130 - not a traceback, and not the link
    watchdog stopping the motor LINK_TIMEOUT_MS later with a latched LINK fault.
    The test runner's own SIGINT is ignored while the command starts, as in a
    background job: the command must hear the Ctrl-C all the same."""
    old = signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        p = _start(["-u", url, "move", "3rev", "--trapezoid", "--relative", "--unhomed", "--enable",
                    "--wait", "20"], user_env)
    finally:
        signal.signal(signal.SIGINT, old)
    try:
        for line in p.stderr:                               # the progress bar: it is moving
            if "moving" in line and "0.0 %" not in line:
                break
        else:
            pytest.fail(f"the move never started: {p.stdout.read()}")
        p.send_signal(sig)
        out, err = p.communicate(timeout=20)
    finally:
        if p.poll() is None:
            p.kill()
    assert p.returncode == cli.EXIT_INTERRUPTED, err
    assert "Traceback" not in err and err.strip().splitlines()[-1] == "torqueloop: interrupted; every axis disabled", err
    st = json.loads(subprocess.run([sys.executable, "-m", "torqueloop.cli", "-u", url, "--json", "status"],
                                   env=user_env, capture_output=True, text=True, timeout=60).stdout)["0"]
    assert not st["enabled"] and st["fault_names"] == [], st


def test_plot_without_a_display_refuses_in_one_line(url, user_env) -> None:
    t0 = time.monotonic()
    r = subprocess.run([sys.executable, "-m", "torqueloop.cli", "-u", url, "plot", "--duration", "2"],
                       env=user_env, capture_output=True, text=True, timeout=60)
    assert r.returncode == 2 and len(r.stderr.strip().splitlines()) == 1 and "--save" in r.stderr, r.stderr
    assert time.monotonic() - t0 < 20


def _start(args: list[str], env: dict[str, str]) -> subprocess.Popen:
    return terminal.cli(args, env, stdout=subprocess.PIPE, stderr=subprocess.PIPE)


def test_server_protocol_errors_are_answers_not_disconnects(url, user_env) -> None:
    """A dashboard's malformed request gets an error line; the connection stays usable."""
    import socket

    srv = _start(["-u", url, "serve", "--port", "0", "--quiet"], user_env)
    try:
        addr = srv.stdout.readline().split(" on ")[1].split()[0]
        host, port = addr.rsplit(":", 1)
        with socket.create_connection((host, int(port)), timeout=30) as s:
            f = s.makefile("rw")
            hello = json.loads(f.readline())
            assert hello["protocol"] == "torqueloop-serve" and hello["identity"]["axis_count"] == 2
            assert hello["key_id"]                                  # keyed, yet the key itself never sent
            for req, kind in (("not json", "BadRequest"), ('{"id": 1, "method": "nope"}', "BadRequest"),
                              ('{"id": 2, "method": "move", "params": {"axis": 0, "target": 100}}',
                               "CommandRejected")):          # disabled and not homed: the board refuses
                f.write(req + "\n")
                f.flush()
                assert json.loads(f.readline())["error"]["kind"] == kind, req
            f.write('{"id": 3, "method": "status", "params": {"axis": 1}}\n')
            f.flush()
            got = json.loads(f.readline())
            assert got["id"] == 3 and "position" in got["result"]
    finally:
        srv.send_signal(signal.SIGINT)
        srv.wait(10)


def test_monitor_move_and_drive_side_by_side_through_serve(url, user_env) -> None:
    srv = _start(["-u", url, "serve", "--port", "0", "--quiet"], user_env)
    try:
        line = srv.stdout.readline()
        assert "torqueloop server for" in line, line + srv.stderr.read()
        assert hserve.find_server(url) is not None          # the CLI finds it by the board's URL
        mon = _start(["-u", url, "--json", "monitor", "--duration", "8", "--every", "2"], user_env)
        first = mon.stdout.readline()                       # monitor is streaming before the move starts
        assert not json.loads(first)["axes"][0]["enabled"]
        r = subprocess.run([sys.executable, "-m", "torqueloop.cli", "-u", url, "--json", "move", "1rev",
                            "--relative", "--unhomed", "--enable", "--wait", "15", "--tolerance", "40"],
                           env=user_env, capture_output=True, text=True, timeout=60)
        assert r.returncode == 0, r.stderr
        moved = json.loads(r.stdout.strip().splitlines()[-1])
        assert moved["settled"] is True
        # open-loop drive from another process through the same server (its DRIVE goes over the server's session)
        d = subprocess.run([sys.executable, "-m", "torqueloop.cli", "-u", url, "--json", "drive", "5%", "--for", "1"],
                           env=user_env, capture_output=True, text=True, timeout=60)
        assert d.returncode == 0 and "Traceback" not in d.stderr, d.stderr
        drove = json.loads(d.stdout.strip().splitlines()[-1])
        assert drove["sign_matches"] and drove["moved_counts"] > 50 and not drove["faults"], drove
        out, err = mon.communicate(timeout=60)
        assert mon.returncode == 0, err
        recs = [json.loads(x) for x in [first, *out.splitlines()] if x.strip()]
        pos = [r["axes"][0]["position"] for r in recs]
        assert any(r["axes"][0]["enabled"] for r in recs), "the monitor never saw the axis enabled"
        assert max(pos) - min(pos) >= 8000, (min(pos), max(pos))   # it watched the whole turn
        st = subprocess.run([sys.executable, "-m", "torqueloop.cli", "-u", url, "--json", "status"],
                            env=user_env, capture_output=True, text=True, timeout=60)
        s = json.loads(st.stdout)["0"]
        assert s["fault_names"] == [] and not s["enabled"], s
    finally:
        srv.send_signal(signal.SIGINT)
        srv.wait(10)
    assert hserve.find_server(url) is None                  # the state file went with it


@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM], ids=["ctrl-c", "kill"])
def test_stopping_the_server_disables_what_its_clients_hold(url, user_env, sig) -> None:
    """Ctrl-C (or a service manager's SIGTERM) on `serve` while a client's drive holds an axis
    and another client streams telemetry: the server disables the axis once (stopping, or as the
    drive's connection closes, whichever comes first), says so in one line, exits 0 with no
    traceback from the clients' threads; the board is left disabled with no fault (the link
    watchdog did not have to stop it); the drive ends in one line."""
    srv = _start(["-u", url, "serve", "--port", "0"], user_env)
    line = srv.stdout.readline()
    assert "torqueloop server for" in line, line + srv.stderr.read()
    mon = _start(["-u", url, "--json", "monitor", "--duration", "30"], user_env)
    drv = _start(["-u", url, "drive", "5%", "--for", "30"], user_env)
    try:
        assert drv.stdout.readline().startswith("t "), "the drive never sampled"  # the axis is enabled, driven
        srv.send_signal(sig)
        out, err = srv.communicate(timeout=20)
    finally:
        srv.kill()
    _, derr = drv.communicate(timeout=20)
    mon.communicate(timeout=20)
    log = out + err
    print(log)
    assert srv.returncode == 0, log
    # the axis disabled exactly once: by the server stopping, or by the drive's release if its
    # connection closed first (both under the board's lock, before the link closes)
    once = log.count("disabled axes [0] (server stopping)") + log.count("left holding axes [0]: disabled them")
    assert once == 1 and "could not" not in log, log
    assert "Traceback" not in log + derr and drv.returncode != 0 and len(derr.strip().splitlines()) <= 2, derr
    r = subprocess.run([sys.executable, "-m", "torqueloop.cli", "-u", url, "--json", "status", "--axis", "0"],
                       env=user_env, capture_output=True, text=True, timeout=60)
    s = json.loads(r.stdout)["0"]
    assert not s["enabled"] and s["fault_names"] == [], s


def test_shell_with_history_completion_and_a_live_plot(url, user_env, tmp_path: Path) -> None:
    pexpect = pytest.importorskip("pexpect")
    frames = tmp_path / "frames.txt"
    sh = pexpect.spawn(sys.executable, ["-m", "torqueloop.cli", "-u", url, "shell", "--plot-file", str(frames)],
                       env=user_env, encoding="utf-8", timeout=60, dimensions=(60, 200))
    try:
        sh.expect("own session")
        sh.expect_exact("torqueloop> ")
        sh.send("sta\t")                   # completion of the CLI's commands
        sh.expect_exact("status")
        sh.sendline("")
        sh.expect("axis 0: ")
        sh.expect_exact("torqueloop> ")
        sh.sendline("serve")
        sh.expect("not inside the shell")
        sh.expect_exact("[exit 2]")
        sh.expect_exact("torqueloop> ")
        sh.sendline("set limit_sw 0")      # `home here` is for an axis without switches
        sh.expect_exact("torqueloop> ")
        sh.sendline("home here")
        sh.expect_exact("torqueloop> ")
        sh.sendline("enable")              # held by the shell's session: the watchdog is fed between commands
        sh.expect_exact("torqueloop> ")
        time.sleep(1.0)                    # twice the 500 ms link watchdog at the prompt
        sh.sendline("status")
        sh.expect("axis 0: ENABLED")
        sh.expect_exact("torqueloop> ")
        sh.sendline("move 2mm --wait 10 --tolerance 40")
        sh.expect("settled at")
        sh.expect_exact("torqueloop> ")
        sh.sendline("status")
        sh.expect(r"axis 0: disabled, homed; position (\d+) counts.*faults: none")
        assert abs(int(sh.match.group(1)) - 4200) <= 60
        sh.expect_exact("torqueloop> ")
        sh.sendline("set limit_sw 1")      # the board as the other tests of this module found it
        sh.expect_exact("torqueloop> ")
        sh.sendline("quit")
        sh.expect(pexpect.EOF)
    finally:
        sh.close(force=True)
    assert sh.exitstatus == 0, sh.before
    assert "move 2mm --wait 10 --tolerance 40" in (Path(user_env["TORQUELOOP_STATE_DIR"]) / "shell_history").read_text()
    text = frames.read_text()
    assert text.count("frame ") >= 2 and "position [mm]" in text and "PWM command" in text
    last = text.strip().split("\n\n")[-1]
    assert "* position 1.9" in last or "* position 2.0" in last, last
