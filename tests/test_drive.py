# SPDX-License-Identifier: MIT
"""Open-loop drive (DRIVE, docs/protocol.md; ``torqueloop drive``, docs/host.md).

On the simulated board's firmware in simulated time (the servo C around the
plant): the drive turns the motor the way its sign says and every check of a
closed-loop move still guards it - RUNAWAY with a frozen encoder, the limit
switch, the soft limit, the link watchdog, the e-stop - and it is refused
while the axis is disabled, above CMD_LIMIT, toward a tripped switch and
without a MAC.  Through the CLI against ``torqueloop sim`` in its own process
(real time, over TCP, as a user): ``drive 5%`` counts up, ``drive -5%`` counts
down, the axis is disabled afterwards with no fault, and the tool refuses
above CMD_LIMIT, without a key, and a duty without its percent sign, each
in one line before the axis is enabled.
"""

from __future__ import annotations

import os

import pytest

from simproc import run_cli as run
from simproc import sim_board
from test_safety_simboard import PERIOD_S, Host
from torqueloop.sim.simboard import LIM_POS, SimBoard
from torqueloop.spec import auth
from torqueloop.spec import protocol as P


@pytest.fixture()
def host() -> Host:
    return Host(SimBoard(key=auth.TEST_KEY))


def drive(host: Host, axis: int, duty: int) -> int:
    return host.cmd("DRIVE", axis=axis, duty=duty)["status"]


@pytest.mark.parametrize("axis", [0, 1])
def test_drive_turns_the_motor_the_way_its_sign_says_and_stop_holds(host: Host, axis: int) -> None:
    b = host.b
    host.ok("ENABLE", mask=1 << axis, enable=1)
    moved = {}
    for duty in (60, -60):
        start = b.plant.count(axis)
        assert drive(host, axis, duty) == P.STATUS["OK"]
        host.run(0.6)
        st = host.ok("STATUS", axis=axis)
        moved[duty] = b.plant.count(axis) - start
        assert st["enabled"] and st["faults"] == 0 and st["pwm_cmd"] == duty, st
        assert b.drive(axis)["cmd"] == duty and (st["velocity_q8"] > 0) == (duty > 0), st
        # STOP ends the drive: the position law holds where the axis is
        host.ok("STOP", mask=1 << axis)
        host.run(0.6)
        st = host.ok("STATUS", axis=axis)
        assert st["enabled"] and st["faults"] == 0 and abs(st["setpoint"] - st["position"]) < 200, st
        assert abs(st["pwm_cmd"]) < 60
    assert moved[60] > 100 and moved[-60] < -100, moved
    host.ok("ENABLE", mask=1 << axis, enable=0)
    assert b.drive(axis)["cmd"] == 0 and not b.drive(axis)["on"]


def test_drive_is_refused_disabled_above_cmd_limit_and_without_a_mac(host: Host) -> None:
    assert drive(host, 0, 50) == P.STATUS["STATE"]                 # disabled
    host.set(0, "CMD_LIMIT", 40)
    host.ok("ENABLE", mask=1, enable=1)
    assert drive(host, 0, 41) == P.STATUS["RANGE"]
    assert drive(host, 0, -41) == P.STATUS["RANGE"]
    assert drive(host, 2, 10) == P.STATUS["BAD_ARG"]
    host.seq += 1
    host.b.write(P.request("DRIVE", host.seq, axis=0, duty=30))     # no MAC
    assert host._reply("DRIVE")["status"] == P.STATUS["AUTH"]
    assert drive(host, 0, 40) == P.STATUS["OK"]                    # at the limit: fine
    host.run(2 * PERIOD_S)
    assert host.b.drive(0)["cmd"] == 40


def test_the_e_stop_ends_a_drive_and_refuses_the_next(host: Host) -> None:
    b = host.b
    host.ok("ENABLE", mask=1, enable=1)
    host.ok("DRIVE", axis=0, duty=80)
    host.run(0.3)
    b.set_estop(True)
    host.run(2 * PERIOD_S)
    st = host.ok("STATUS", axis=0)
    assert not st["enabled"] and st["faults"] & P.FAULT["ESTOP"] and b.drive(0)["cmd"] == 0, st
    assert host.cmd("ENABLE", mask=1, enable=1)["status"] == P.STATUS["STATE"]
    assert drive(host, 0, 80) == P.STATUS["STATE"]


def test_a_frozen_encoder_trips_runaway_under_the_drive(host: Host) -> None:
    b = host.b
    host.set(0, "LAW", 0)         # no position law: a command after the fault could only be the drive's
    host.ok("ENABLE", mask=1, enable=1)
    b.set_encoder_fault(0, "frozen")
    host.ok("DRIVE", axis=0, duty=200)                               # above STALL_CMD (100)
    t0 = b.t
    t_off = host.run(3.0, until=lambda: not b.drive(0)["on"])
    st = host.ok("STATUS", axis=0)
    stall_s = P.PARAMS["STALL_MS"].default / 1000
    assert st["faults"] == P.FAULT["RUNAWAY"] and not st["enabled"], st
    # the stall check trips by STALL_MS; the encoder plausibility check (docs/safety.md) may trip first
    assert 0 < t_off - t0 <= stall_s + 3 * PERIOD_S, t_off - t0
    # the fault ended the drive: enabling again (after clearing) does not resume it
    b.set_encoder_fault(0, None)
    host.run(0.1)
    host.ok("CLEAR_FAULT", mask=1)
    host.ok("ENABLE", mask=1, enable=1)
    host.run(0.2)
    assert host.ok("STATUS", axis=0)["pwm_cmd"] == 0


def test_the_limit_switch_stops_the_drive_and_blocks_that_direction(host: Host) -> None:
    b = host.b
    b.limit_counts[0] = (-100_000, 1500)
    host.ok("ENABLE", mask=1, enable=1)
    host.ok("DRIVE", axis=0, duty=150)
    t = host.run(5.0, until=lambda: not b.drive(0)["on"])
    assert t > 0 and b.limits(0) == LIM_POS
    st = host.ok("STATUS", axis=0)
    assert st["faults"] == P.FAULT["LIMIT_POS"], st
    host.ok("ENABLE", mask=1, enable=1)                              # a direction fault: allowed
    assert drive(host, 0, 100) == P.STATUS["RANGE"]                  # further in: refused
    assert drive(host, 0, -100) == P.STATUS["OK"]                    # back out: fine
    host.run(2.0)
    assert b.limits(0) == 0 and host.ok("STATUS", axis=0)["enabled"]


def test_the_soft_limit_stops_the_drive(host: Host) -> None:
    b = host.b
    host.set(0, "SOFT_MAX", b.encoder_count(0) + 1000)
    host.ok("ENABLE", mask=1, enable=1)
    host.ok("DRIVE", axis=0, duty=150)
    t = host.run(5.0, until=lambda: not b.drive(0)["on"])
    st = host.ok("STATUS", axis=0)
    assert t > 0 and st["faults"] == P.FAULT["SOFT_LIMIT"] and not st["enabled"], st


def test_a_silent_host_trips_the_link_watchdog_under_the_drive(host: Host) -> None:
    b = host.b
    host.ok("ENABLE", mask=1, enable=1)
    host.ok("DRIVE", axis=0, duty=80)
    t0 = b.t
    while b.t - t0 < 1.0 and b.drive(0)["on"]:                       # no heartbeat
        b.advance(PERIOD_S)
        b.read()
    st = host.ok("STATUS", axis=0)
    timeout_s = P.PARAMS["LINK_TIMEOUT_MS"].default / 1000
    assert st["faults"] == P.FAULT["LINK"] and not st["enabled"], st
    assert timeout_s <= b.t - t0 <= timeout_s + 3 * PERIOD_S


# ---- the CLI against `torqueloop sim` ----------------------------------------------

@pytest.fixture(scope="module")
def url(tmp_path_factory):
    path = tmp_path_factory.mktemp("key") / "link.key"
    auth.write_key_file(path, auth.new_key())
    env = dict(os.environ, **{auth.KEY_FILE_ENV: str(path)})
    old = os.environ.get(auth.KEY_FILE_ENV)
    os.environ[auth.KEY_FILE_ENV] = str(path)
    with sim_board("sim", "--port", "0", env=env) as u:
        yield u
    if old is None:
        del os.environ[auth.KEY_FILE_ENV]
    else:
        os.environ[auth.KEY_FILE_ENV] = old


def test_cli_drive_both_ways_reads_the_encoder_sign_and_disables(url, capsys) -> None:
    up, _ = run(url, capsys, "drive", "5%", "--for", "1")
    down, _ = run(url, capsys, "drive", "-5%", "--for", "1")
    print(f"drive 5%: {up['moved_counts']:+d} counts, drive -5%: {down['moved_counts']:+d} counts in about 1 s")
    assert up["duty_steps"] == 51 and down["duty_steps"] == -51
    assert up["moved_counts"] > 100 and down["moved_counts"] < -100
    assert up["sign_matches"] and down["sign_matches"] and not up["faults"] and not down["faults"]
    assert len(up["samples"]) >= 5 and all(s["pwm_cmd"] == 51 for s in up["samples"])
    st, _ = run(url, capsys, "status", "--axis", "0")
    assert st["0"]["enabled"] == 0 and st["0"]["faults"] == 0


def test_cli_drive_lasts_its_time_on_a_board_slower_than_real_time(tmp_path, capsys, monkeypatch) -> None:
    """--for counts the board's time (its telemetry's clock): a board living a quarter
    second per second of the host's is driven a whole simulated second, as fast as the
    one above, and the samples are a tenth of a second of its time apart."""
    path = tmp_path / "link.key"
    auth.write_key_file(path, auth.new_key())
    monkeypatch.setenv(auth.KEY_FILE_ENV, str(path))
    with sim_board("sim", "--port", "0", "--speed", "0.25", env=dict(os.environ)) as slow:
        up, _ = run(slow, capsys, "drive", "5%", "--for", "1")
    print(f"drive 5% for 1 s on a board at 0.25 x real time: {up['moved_counts']:+d} counts in {up['seconds']} s")
    assert up["moved_counts"] > 100 and up["sign_matches"] and not up["faults"], up
    assert 1.0 <= up["seconds"] <= 1.2, up
    gaps = [b["t_s"] - a["t_s"] for a, b in zip(up["samples"], up["samples"][1:])]
    assert len(up["samples"]) >= 10 and all(0.05 <= g <= 0.15 for g in gaps), gaps


def test_cli_drive_sets_and_restores_the_carrier(url, capsys) -> None:
    before, _ = run(url, capsys, "get", "pwm_freq", "--axis", "1")
    res, _ = run(url, capsys, "drive", "10%", "-a", "1", "--pwm-freq", "5000", "--for", "0.5")
    assert abs(res["pwm_freq_hz"] - 5000) < 200 and res["moved_counts"] > 0
    after, _ = run(url, capsys, "get", "pwm_freq", "--axis", "1")
    assert after == before


def test_cli_drive_refusals_are_one_line_and_leave_the_axis_disabled(url, capsys, monkeypatch) -> None:
    run(url, capsys, "set", "CMD_LIMIT", "40")
    try:
        _, err = run(url, capsys, "drive", "5%", rc=2)
        assert "CMD_LIMIT" in err and "51 steps" in err
    finally:
        run(url, capsys, "set", "CMD_LIMIT", "1023")
    _, err = run(url, capsys, "drive", "5", rc=2)
    assert "percent" in err
    _, err = run(url, capsys, "drive", "120%", rc=2)
    assert "outside" in err
    monkeypatch.delenv(auth.KEY_FILE_ENV)
    _, err = run(url, capsys, "drive", "5%", rc=1)
    assert "needs the link key" in err
    st, _ = run(url, capsys, "status", "--axis", "0")
    assert st["0"]["enabled"] == 0
