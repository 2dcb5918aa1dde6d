# SPDX-License-Identifier: MIT
"""End to end: the ``torqueloop`` command against the simulated board over TCP.

``torqueloop sim`` runs in its own process (the servo firmware's C and the
plant model, real time, sending ``*HELLO*`` on every connect like an
unconfigured RN-XV); every command here goes through the CLI's ``main`` with
``--json``, over a fresh TCP connection, exactly as a user's would.
Checked: info, set/get round trips in physical units, a move the plant
follows, a step test's files and figures, a following-error fault decoded
and cleared, config save/load round trip (and the characterisation file),
an upload that changes the build id, and a corrupted one that the boot ROM
refuses, leaving the factory firmware working; the careless user of
Every bad value refused with one line and exit status 2 before
anything is sent, a refused `move --enable` that leaves the axis disabled, a
step beyond the following limit refused with the reason, a busy board named
busy, safety limits that cannot be loosened while an axis is enabled, and
`get` reading back what `set` wrote at the extremes of the gains.  The
simulated board and the tool share a key file through
``$TORQUELOOP_KEY_FILE`` (docs/security.md); without it, with a wrong one, or
against a board without a key, the tool says so in one line and stop /
disable still work.

Tests may run in any order and on different pytest-xdist workers (each its
own simulated board), so each one sets up the state it needs.
"""

from __future__ import annotations

import json
import os
from pathlib import Path

import pytest

from simproc import run_cli as run
from simproc import sim_board
from torqueloop import cli
from torqueloop.spec import auth
from torqueloop.spec import protocol as P

BUILD_ID = 0x0DDC0DE5


@pytest.fixture(scope="module")
def keyfile(tmp_path_factory):
    """The key the simulated board is built with and the tool reads, named by
    $TORQUELOOP_KEY_FILE for the whole module (as a user would set it)."""
    path = tmp_path_factory.mktemp("key") / "link.key"
    auth.write_key_file(path, auth.new_key())
    old = os.environ.get(auth.KEY_FILE_ENV)
    os.environ[auth.KEY_FILE_ENV] = str(path)
    yield path
    if old is None:
        del os.environ[auth.KEY_FILE_ENV]
    else:
        os.environ[auth.KEY_FILE_ENV] = old


def _sim(keyless: bool = False):
    env = {k: v for k, v in os.environ.items() if not (keyless and k == auth.KEY_FILE_ENV)}
    with sim_board("sim", "--port", "0", "--hello", "--build-id", hex(BUILD_ID), env=env) as url:
        yield url


@pytest.fixture(scope="module")
def url(keyfile):
    yield from _sim()


def test_info(url, capsys) -> None:
    info, _ = run(url, capsys, "info")
    assert info["build_id"] == f"0x{BUILD_ID:08x}"
    assert info["axis_count"] == 2 and info["clk_hz"] == 50_000_000
    # The *HELLO* the server sends on connect is either skipped and counted, or gone before the
    # tool reads: pyserial's socket:// open() empties the input once connected
    # (reset_input_buffer), and a server that answers the connect before that call loses it
    # there - a race a loaded machine decided once.  Either way it costs the exchange nothing
    # (the counting itself: tests/test_host_client.py, with the hello before a reply).
    hc = info["host_counters"]
    assert hc["text_bytes"] in (0, len("*HELLO*")), hc
    assert hc["retries"] == 0 and hc["crc_errors"] == 0 and hc["bad_chunks"] == hc["text_bytes"] // 7, hc


def test_set_get_round_trip_in_physical_units(url, capsys) -> None:
    for name, value, tol in (("kp", "0.61", 1e-4), ("kd", "0.013", 1e-4), ("pwm_freq", "200", 2.0),
                             ("period", "0.01", 0), ("tau_max", "2.2", 0)):
        run(url, capsys, "set", name, value, "--axis", "1")
        got, _ = run(url, capsys, "get", name, "--axis", "1")
        assert abs(got[name]["value"] - float(value)) <= tol, (name, got)
    run(url, capsys, "set", "law", "pid", "--axis", "1")
    got, _ = run(url, capsys, "get", "law", "--axis", "1")
    assert got["law"]["value"] == "pid"
    run(url, capsys, "set", "period", "0.025")
    # out of range: refused by the tool with the limits named, nothing changed
    _, err = run(url, capsys, "set", "cmd_limit", "4000", rc=2)
    assert "outside" in err and "1023" in err
    got, _ = run(url, capsys, "get", "cmd_limit")
    assert got["cmd_limit"]["value"] == 1023


def test_move_is_followed_by_the_plant(url, capsys) -> None:
    run(url, capsys, "disable", "--all")
    run(url, capsys, "clear-fault", "--all")
    run(url, capsys, "move", "2mm", "--enable", "--axis", "0", rc=1)     # not homed
    _, err = run(url, capsys, "home", "here", "--axis", "0", rc=1)       # the simulated stage has switches
    assert "HAS_SWITCHES" in err and "home neg" in err
    run(url, capsys, "set", "limit_sw", "0", "--axis", "0")
    run(url, capsys, "home", "here", "--axis", "0")
    # P control with the paper's gain stops within some tens of counts (stiction): settled within 40
    res, _ = run(url, capsys, "move", "2mm", "--enable", "--wait", "15", "--tolerance", "40", "--axis", "0")
    assert res["target_counts"] == 4200          # 2 mm at 4 mm and 8400 counts per turn
    assert res["settled"] and abs(res["error_counts"]) <= 40, res
    st, _ = run(url, capsys, "status", "--axis", "0")
    assert abs(st["0"]["position"] - 4200) <= 40
    assert st["0"]["overruns"] == 0, st        # decoded from STATUS; no period missed
    run(url, capsys, "disable", "--all")


def test_step_test_writes_plot_csv_and_figures(url, capsys, tmp_path: Path) -> None:
    run(url, capsys, "clear-fault", "--all")
    res, _ = run(url, capsys, "step-test", "1rev", "--relative", "--unhomed", "--duration", "3", "--out", str(tmp_path))
    f = res["figures"]
    for ext in ("png", "csv", "json"):
        assert (tmp_path / f"step_axis0.{ext}").stat().st_size > 100
    assert f["faults"] == [] and f["records"] > 80
    assert f["target_counts"] - f["start_counts"] == 8400
    # P control of axis x with the paper's Table 1 gain: it gets there
    assert abs(f["steady_state_error_counts"]) < 200     # 2.4 % of the step after 3 s
    assert 0 < f["rise_time_s"] < 1.5 and f["settling_time_s"] is not None
    assert f["rmse_counts"] > 0
    csv_lines = (tmp_path / "step_axis0.csv").read_text().splitlines()
    assert csv_lines[0].startswith("t_s,setpoint_0_counts") and len(csv_lines) == f["records"] + 1


def test_fault_is_decoded_and_cleared(url, capsys) -> None:
    run(url, capsys, "disable", "--all")
    run(url, capsys, "clear-fault", "--all")
    run(url, capsys, "set", "follow_limit", "50", "--axis", "1")
    # a step that large would trip at once: refused up front, with the reason, axis left disabled
    _, err = run(url, capsys, "move", "3000", "--relative", "--enable", "--unhomed", "--axis", "1", rc=2)
    assert "FOLLOW_LIMIT" in err and "--trapezoid" in err
    st, _ = run(url, capsys, "status", "--axis", "1")
    assert st["1"]["enabled"] == 0
    # a profiled move the heavy z axis cannot follow within 50 counts
    _, err = run(url, capsys, "move", "3000", "--relative", "--enable", "--unhomed", "--trapezoid", "--wait", "3",
                 "--axis", "1", rc=1)
    st, _ = run(url, capsys, "status", "--axis", "1")
    assert "FOLLOWING" in st["1"]["fault_names"] and st["1"]["enabled"] == 0
    _, err = run(url, capsys, "enable", "--axis", "1", rc=1)
    assert "FOLLOWING" in err and "clear-fault" in err
    res, _ = run(url, capsys, "clear-fault", "--axis", "1")
    assert "FOLLOWING" in res["before"]["1"] and res["after"]["1"] == []
    run(url, capsys, "set", "follow_limit", "16800", "--axis", "1")
    run(url, capsys, "enable", "--axis", "1")
    run(url, capsys, "disable", "--axis", "1")


def test_config_save_load_round_trip(url, capsys, tmp_path: Path) -> None:
    a, b = tmp_path / "a.json", tmp_path / "b.json"
    run(url, capsys, "disable", "--all")
    run(url, capsys, "config", "save", str(a))
    doc = json.loads(a.read_text())
    assert doc["firmware"]["build_id"] == f"0x{BUILD_ID:08x}"
    kp0 = doc["axes"][0]["KP_Q16"]
    run(url, capsys, "set", "kp", "0.3")
    run(url, capsys, "set", "soft_max", "-5", "--axis", "1")
    run(url, capsys, "set", "soft_min", "-9", "--axis", "1")
    run(url, capsys, "config", "load", str(a))
    got, _ = run(url, capsys, "get", "KP_Q16")
    assert got["KP_Q16"]["raw"] == kp0
    run(url, capsys, "config", "save", str(b))
    assert a.read_text() == b.read_text()
    # a file saved under an older protocol whose parameters mean the same loads; one older or newer is refused
    assert doc["firmware"]["proto_version"] == P.PROTO_VERSION
    for pv, rc in ((P.CONFIG_SINCE, 0), (P.CONFIG_SINCE - 1, 1), (P.PROTO_VERSION + 1, 1)):
        a.write_text(json.dumps({**doc, "firmware": {**doc["firmware"], "proto_version": pv}}))
        _, err = run(url, capsys, "config", "load", str(a), rc=rc)
        assert rc == 0 or f"saved with protocol {pv}" in err
    # a file from another build is refused unless forced; a broken one names its field
    doc["firmware"]["build_id"] = "0x00000001"
    a.write_text(json.dumps(doc))
    _, err = run(url, capsys, "config", "load", str(a), rc=1)
    assert "0x00000001" in err and "--force" in err
    doc["axes"][1]["PW0"] = 5000
    a.write_text(json.dumps(doc))
    _, err = run(url, capsys, "config", "load", str(a), "--force", rc=2)
    assert "axes[1].PW0" in err
    # a file that is no configuration at all: one line, exit status 2
    for name, text in (("nested.json", "[" * 100_000 + "]" * 100_000), ("firmware.json", json.dumps({**doc, "firmware": "x"})),
                       ("garbage.json", "{not json"), ("global.json", json.dumps({**doc, "global": {"PERIOD_US": 1e99}}))):
        (tmp_path / name).write_text(text)
        _, err = run(url, capsys, "config", "load", str(tmp_path / name), rc=2)
        assert name in err
    (tmp_path / "binary.json").write_bytes(b"\xff\xfe\x00garbage")
    run(url, capsys, "config", "load", str(tmp_path / "binary.json"), rc=2)


def test_config_load_takes_the_characterisation_file(url, capsys, tmp_path: Path) -> None:
    from torqueloop.spec.pwm import carrier_hz, divider_for

    axes = {}
    for name, f, pw0 in (("x", 450.0, 31), ("z", 200.0, 44)):
        cm = divider_for(f)
        ach = carrier_hz(cm)
        axes[name] = {"motor": name, "pwm_freq_hz": ach, "count_max": cm, "achieved_hz": ach,
                      "freq_error_pct": 0.0, "pw0_counts": pw0, "pw_max_counts": 1000, "tau_max_nm": 2.31,
                      "duty_pw0_pct": pw0 / 10.23, "duty_pwf_pct": 97.75, "torque_per_count_nm": 0.0024,
                      "step7": {}, "provenance": {}}
    p = tmp_path / "characterization.json"
    p.write_text(json.dumps({"schema": "torqueloop-characterization", "schema_version": 1,
                             "clk_hz": 50_000_000, "pwm_bits": 10, "axes": axes, "provenance": {}}))
    run(url, capsys, "config", "load", str(p))
    for axis, name in ((0, "x"), (1, "z")):
        got, _ = run(url, capsys, "get", "pw0", "pwmax", "FDIV", "tau_max", "--axis", str(axis))
        assert got["pw0"]["raw"] == axes[name]["pw0_counts"] and got["pwmax"]["raw"] == 1000
        assert got["FDIV"]["raw"] == axes[name]["count_max"] and got["tau_max"]["raw"] == 2310


@pytest.fixture(scope="module")
def servo_image() -> Path:
    from torqueloop.flow.firmware import build

    return build("servo_e2e").elf


@pytest.fixture()
def own_url(keyfile):
    """A simulated board for one test: after an upload the module's board
    would answer with another build id than the tests after it expect."""
    yield from _sim()


def test_upload_changes_the_build_id(own_url, capsys, tmp_path: Path, servo_image: Path) -> None:
    bp = pytest.importorskip("torqueloop.spec.bootproto")
    image = bp.load_image(servo_image)
    res, _ = run(own_url, capsys, "upload", str(servo_image))
    assert res["ok"] and res["bootloader_replies"][:2] == ["W", "K"]
    # the simulated board reports the running image's CRC-32 as its build id
    assert res["new_build_id"] == f"0x{bp.crc32(image):08x}" != res["old_build_id"]
    info, _ = run(own_url, capsys, "info")
    assert info["build_id"] == res["new_build_id"]


class FlipOneImageByte:
    """The link, with one byte of the upload frame's image changed on the way."""

    def __init__(self, link, at: int) -> None:
        self.link, self.at, self.sent = link, at, 0

    def write(self, data: bytes) -> int:
        b = bytearray(data)
        if self.sent <= self.at < self.sent + len(b):
            b[self.at - self.sent] ^= 0x40
        self.sent += len(b)
        return self.link.write(bytes(b))

    def __getattr__(self, name: str):
        return getattr(self.link, name)


def test_corrupted_upload_is_refused_and_the_board_keeps_working(url, capsys, tmp_path: Path) -> None:
    bp = pytest.importorskip("torqueloop.spec.bootproto")
    from torqueloop.host.client import Client
    from torqueloop.host.transport import open_link
    from torqueloop.host.upload import run_upload

    link, info = open_link(url)
    c = Client(link, info, key=auth.read_key_file(os.environ[auth.KEY_FILE_ENV]))
    try:
        r = run_upload(c, os.urandom(2000), port=FlipOneImageByte(link, bp.FRAME_OVERHEAD + 1500))
    finally:
        c.close()
    assert not r.ok and "CRC-32" in r.message and "factory" in r.message
    assert r.replies == ["W", "C", "F"]
    assert r.new_build_id == BUILD_ID
    # signed with another key: the boot ROM says A and starts the factory firmware
    link, info = open_link(url)
    c = Client(link, info, key=auth.read_key_file(os.environ[auth.KEY_FILE_ENV]))
    try:
        from torqueloop.host import upload as up
        res = up.upload("", os.urandom(1000), key=bytes(32), port=link, enter=b"", wait_window_s=0)
        assert not res.ok        # no window open: nothing was sent
        c.connect()
        c.raw_tap = bytearray()
        c.bootloader()
        c.pump(0.2)
        assert b"TLBW" in c.raw_tap
        c.raw_tap = None
        res = up.upload("", os.urandom(1000), key=bytes(32), port=link, wait_window_s=0)
    finally:
        c.close()
    assert not res.ok and "authentication failed" in res.message and res.factory_running
    assert r.new_build_id == BUILD_ID               # the factory firmware answers
    # ... and works: a move the plant follows
    run(url, capsys, "clear-fault", "--all")
    res, _ = run(url, capsys, "move", "1000", "--relative", "--enable", "--unhomed", "--wait", "15",
                 "--tolerance", "40")
    assert res["settled"] and abs(res["error_counts"]) <= 40
    run(url, capsys, "disable", "--all")
    # a damaged file, or anything but a firmware image for this board, is refused before anything is sent
    bad = tmp_path / "bad.elf"
    bad.write_bytes(b"\x7fELF\x01\x01" + bytes(10))
    _, err = run(url, capsys, "upload", str(bad), rc=2)
    assert "bad.elf" in err
    (tmp_path / "notes.txt").write_text("hello world\n")              # 12 bytes of text ...
    (tmp_path / "noise.bin").write_bytes(os.urandom(3000))            # ... and 3 kB of random bytes "ran"
    for name in ("notes.txt", "noise.bin"):
        for raw in ([], ["--raw"]):
            _, err = run(url, capsys, "upload", str(tmp_path / name), *raw, rc=2)
            assert name in err and "refused" in err
    info_, _ = run(url, capsys, "info")
    assert info_["build_id"] == f"0x{BUILD_ID:08x}"


def test_no_answer_names_the_likely_cause(capsys) -> None:
    import socket

    s = socket.socket()
    s.bind(("127.0.0.1", 0))
    s.listen(1)                     # accepts, never answers: a bridge whose UART side is dead
    port = s.getsockname()[1]
    try:
        capsys.readouterr()
        rc = cli.main(["-u", f"socket://127.0.0.1:{port}", "--timeout", "0.1", "--retries", "1", "info"])
        err = capsys.readouterr().err
    finally:
        s.close()
    assert rc == 3 and "data mode" in err


def test_a_refused_connection_exits_3_in_one_line(capsys) -> None:
    import socket

    s = socket.socket()
    s.bind(("127.0.0.1", 0))
    port = s.getsockname()[1]
    s.close()                       # nothing listens there: the connection is refused
    capsys.readouterr()
    rc = cli.main(["-u", f"socket://127.0.0.1:{port}", "info"])
    err = capsys.readouterr().err
    assert rc == 3 and "cannot open" in err and len(err.strip().splitlines()) == 1 and "Traceback" not in err


def test_output_cut_short_by_its_reader_is_no_error(url) -> None:
    """`torqueloop info | head -1`, head gone before the tool writes: no broken-pipe message, exit 0."""
    import subprocess
    import sys

    r, w = os.pipe()
    os.close(r)                     # the reader has gone (head -1 after its line)
    try:
        p = subprocess.run([sys.executable, "-m", "torqueloop.cli", "-u", url, "info"], stdout=w,
                           stderr=subprocess.PIPE, text=True, timeout=60)
    finally:
        os.close(w)
    assert p.returncode == 0 and p.stderr == "", p.stderr


BAD_VALUES = [
    ("set", "kp", "inf"), ("set", "kp", "nan"), ("set", "kp", "1e400"), ("set", "kp", "-1"), ("set", "kp", "1e30"),
    ("set", "kp", "abc"), ("set", "KP_Q16", "1.5"), ("set", "KP_Q16", "99999999999"), ("set", "law", "7"),
    ("set", "pwm_freq", "0"), ("set", "period", "inf"), ("set", "nonsense", "1"),
    ("move", "1e400"), ("move", "1e12"), ("move", "inf"), ("move", "nan"), ("move", "12parsecs"),
    ("move", "1", "--axis", "9"), ("move", "1", "--wait", "nan"), ("monitor", "--every", "0"),
    ("--timeout", "-1", "info"), ("--retries", "1e9", "info"), ("step-test", "1e99rev"),
]


@pytest.mark.parametrize("args", BAD_VALUES, ids=[" ".join(a) for a in BAD_VALUES])
def test_every_bad_value_gets_one_line_and_exit_status_2(url, capsys, args) -> None:
    run(url, capsys, *args, rc=2)


def test_pwm_carrier_and_pw0_are_bounded_by_the_tool_and_the_board(url, capsys) -> None:
    run(url, capsys, "disable", "--all")
    _, err = run(url, capsys, "set", "pwm_freq", "100000", rc=2)       # silently 48.9 kHz before
    assert "48876 Hz" in err and "--nearest" in err                    # the divider cannot make it
    _, err = run(url, capsys, "set", "pwm_freq", "100000", "--nearest", rc=2)
    assert "CARRIER" in err and "25000" in err                         # the board's rule: PWM_MAX_HZ
    run(url, capsys, "set", "pwm_freq", "24000", "--nearest")           # 24438 Hz: 1.8 % off
    got, _ = run(url, capsys, "get", "pwm_freq", "FDIV")
    assert got["FDIV"]["raw"] == 2 and got["pwm_freq"]["value"] < 25_000
    run(url, capsys, "set", "pw0", "0")
    run(url, capsys, "set", "pwmax", "800")
    _, err = run(url, capsys, "set", "pw0", "801", rc=2)
    assert "PWMAX" in err
    run(url, capsys, "set", "pw0", "100")
    _, err = run(url, capsys, "set", "pwmax", "99", rc=2)
    assert "PW0" in err
    run(url, capsys, "set", "pwmax", "1023")
    run(url, capsys, "set", "pw0", "0")
    run(url, capsys, "set", "pwm_freq", "450")


def test_safety_limits_only_tighten_while_enabled(url, capsys) -> None:
    run(url, capsys, "disable", "--all")
    run(url, capsys, "clear-fault", "--all")
    run(url, capsys, "set", "link_timeout", "10")
    run(url, capsys, "enable", "--axis", "1")
    for name, looser in (("follow_limit", "20000"), ("soft_max", "2000000"), ("soft_min", "-2000000"),
                         ("link_timeout", "60"), ("cmd_limit", "1023"), ("pwm_freq", "900"), ("stall_cmd", "500")):
        if name == "cmd_limit":
            run(url, capsys, "set", "cmd_limit", "1000")     # tighter: fine
        _, err = run(url, capsys, "set", name, looser, rc=1)
        assert "LOOSEN" in err and "disable" in err, (name, err)
    run(url, capsys, "set", "follow_limit", "8000")          # stricter: fine while enabled
    run(url, capsys, "disable", "--all")
    for name, v in (("follow_limit", "16800"), ("cmd_limit", "1023"), ("link_timeout", "10")):
        run(url, capsys, "set", name, v)


def test_get_reads_back_what_set_wrote_at_every_gain(url, capsys) -> None:
    run(url, capsys, "disable", "--all")
    run(url, capsys, "set", "tau_max", "2.4")
    for name in ("kp", "kd", "ki"):
        for value in ("100", "99.99", "0.000049", "0", "37.5"):
            res, _ = run(url, capsys, "set", name, value)
            got, _ = run(url, capsys, "get", name)
            assert got[name]["value"] == res["value"], (name, value, res, got)
            assert abs(res["value"] - float(value)) <= 0.00005 + float(value) * 1e-4, (name, value, res)
    # a raw gain the physical view cannot show (read back as 100 N m/rad, 1000x too low)
    _, err = run(url, capsys, "set", "KP_Q16", "2147483647", rc=2)
    assert "N m/rad" in err
    run(url, capsys, "set", "kp", "100")
    _, err = run(url, capsys, "set", "tau_max", "1000", rc=2)    # would push kp beyond 100 N m/rad
    run(url, capsys, "set", "kp", "0.82")


def test_a_refused_move_does_not_leave_the_axis_enabled(url, capsys) -> None:
    run(url, capsys, "disable", "--all")
    run(url, capsys, "clear-fault", "--all")
    run(url, capsys, "set", "limit_sw", "0", "--axis", "0")
    run(url, capsys, "home", "here", "--axis", "0")
    got, _ = run(url, capsys, "get", "soft_max")
    _, err = run(url, capsys, "move", str(got["soft_max"]["value"] + 1), "--enable", "--trapezoid", rc=2)
    assert "soft limits" in err
    _, err = run(url, capsys, "move", "20000", "--enable", rc=2)     # a step beyond FOLLOW_LIMIT
    assert "FOLLOW_LIMIT" in err
    st, _ = run(url, capsys, "status", "--axis", "0")
    assert st["0"]["enabled"] == 0 and st["0"]["faults"] == 0


def test_a_busy_board_is_reported_as_busy(url, capsys) -> None:
    import socket

    host, port = url.removeprefix("socket://").split(":")
    holder = socket.create_connection((host, int(port)))       # another client holds the board
    try:
        holder.sendall(b"\x00")
        import time
        time.sleep(0.2)
        _, err = run(url, capsys, "info", rc=3)         # docs/host.md: a refused connection is no answer
    finally:
        holder.close()
    assert "busy" in err and "another client" in err and "reset by peer" not in err.split("(")[0]


def test_key_errors_are_one_line_and_stopping_needs_no_key(url, keyfile, capsys, tmp_path, monkeypatch) -> None:
    run(url, capsys, "disable", "--all")
    run(url, capsys, "set", "limit_sw", "0", "--axis", "0")
    run(url, capsys, "home", "here", "--axis", "0")   # homed: only the key can refuse the moves below
    # no key at all: refused by the tool before anything is sent; reading, stop and disable work
    monkeypatch.delenv(auth.KEY_FILE_ENV)
    _, err = run(url, capsys, "enable", "--axis", "0", rc=1)
    assert "needs the link key" in err and "--key-file" in err and "Traceback" not in err
    st, _ = run(url, capsys, "status", "--axis", "0")
    assert st["0"]["enabled"] == 0
    run(url, capsys, "stop", "--all")
    run(url, capsys, "disable", "--all")
    # a key file that is not there, or not a key file, or readable by others
    _, err = run(url, capsys, "-k", str(tmp_path / "nope.key"), "move", "10", rc=1)
    assert "no key file at" in err and "nope.key" in err
    bad = tmp_path / "bad.key"
    bad.write_text("hello\n")
    bad.chmod(0o600)
    _, err = run(url, capsys, "-k", str(bad), "move", "10", rc=1)
    assert "not a torqueloop key file" in err
    loose = tmp_path / "loose.key"
    loose.write_text(keyfile.read_text())
    loose.chmod(0o644)
    _, err = run(url, capsys, "-k", str(loose), "move", "10", rc=1)
    assert "chmod 600" in err
    _, err = run(url, capsys, "-k", "ab" * 32, "move", "10", rc=1)
    assert "looks like a key" in err                 # a key typed on the command line is refused
    # the wrong key: "authentication failed", at once, and stop/disable still work with it
    wrong = tmp_path / "wrong.key"
    auth.write_key_file(wrong, auth.new_key())
    _, err = run(url, capsys, "-k", str(wrong), "move", "10", "--enable", rc=1)
    assert "authentication failed" in err and "wrong.key" in err
    run(url, capsys, "-k", str(wrong), "disable", "--all")
    # and with the right key the same command runs
    res, _ = run(url, capsys, "-k", str(keyfile), "move", "10", "--relative", "--enable")
    run(url, capsys, "-k", str(keyfile), "disable", "--all")
    info_, _ = run(url, capsys, "info")
    assert "auth" in info_["board_counters"]         # refusals for a MAC are counted on the board


def test_key_files(capsys, tmp_path) -> None:
    p = tmp_path / "new.key"
    assert cli.main(["--json", "key", "new", str(p)]) == 0
    out = json.loads(capsys.readouterr().out)
    assert (p.stat().st_mode & 0o777) == 0o600 and out["key_id"] == auth.key_id(auth.read_key_file(p))
    assert cli.main(["key", "new", str(p)]) == 1 and "never overwritten" in capsys.readouterr().err
    assert cli.main(["-k", str(p), "key", "id"]) == 0 and out["key_id"] in capsys.readouterr().out


@pytest.fixture(scope="module")
def keyless_url(url):
    """A second simulated board, built without a key."""
    yield from _sim(keyless=True)


def test_a_board_without_a_key_says_so(keyless_url, capsys) -> None:
    _, err = run(keyless_url, capsys, "move", "10", "--enable", "--unhomed", rc=1)
    assert "the board has no link key" in err and "Key provisioning" in err
    _, err = run(keyless_url, capsys, "set", "kp", "0.5", rc=1)
    assert "no link key" in err
    run(keyless_url, capsys, "disable", "--all")
    run(keyless_url, capsys, "stop", "--all")
