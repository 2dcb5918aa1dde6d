# SPDX-License-Identifier: MIT
"""Settings that survive (SAVE, docs/firmware.md "Settings that survive";
``torqueloop save``, docs/host.md).

On the simulated board (the servo firmware's C; the configuration flash is
torqueloop/sim/epcs.py, the EPCS command set byte by byte): the saved
parameters come back after a power cycle, the report says when the running
ones differ, saves alternate between the two sectors and never touch the
newest copy, and a power loss during or right after each write of a save
(the sector erase, each page program) leaves either the older copy or the
complete new one - never a mix, never the defaults when something was
saved.  A flash that does not answer makes SAVE fail with STORE.  Through the
CLI against ``torqueloop sim --flash FILE`` in its own process: ``save``,
then a new process on the same file (the power cycle) has the parameters
back, and ``status`` says whether the running ones are the saved ones.
"""

from __future__ import annotations

import os

import pytest

from simproc import run_cli as run
from simproc import sim_board
from test_safety_simboard import Host
from torqueloop.sim.epcs import SECTOR_BYTES
from torqueloop.sim.simboard import SimBoard
from torqueloop.spec import auth
from torqueloop.spec import protocol as P

KP = P.PARAMS["KP_UNM_RAD"].id
PW0 = P.PARAMS["PW0"].id
PERIOD = P.PARAMS["PERIOD_US"].id
SLOTS = {P.STORE["slot_a"], P.STORE["slot_b"]}
#: the saved record (firmware/servo/store.c record_t): magic, seq, layout, every parameter slot of the
#: global array and of each axis's, the CRC; one PAGE PROGRAM per page it touches
RECORD_BYTES = 4 * (3 + (1 + P.AXIS_COUNT) * len(P.PARAMS) + 1)
PAGES = -(-RECORD_BYTES // P.STORE["page_bytes"])


def values(h: Host) -> tuple[int, int, int]:
    return (h.ok("GET_PARAM", axis=0, param=KP)["value"], h.ok("GET_PARAM", axis=1, param=PW0)["value"],
            h.ok("GET_PARAM", axis=P.GLOBAL_AXIS, param=PERIOD)["value"])


def put(h: Host, kp: int, pw0: int, period: int) -> tuple[int, int, int]:
    h.set(0, "KP_UNM_RAD", kp)
    h.set(1, "PW0", pw0)
    h.set(P.GLOBAL_AXIS, "PERIOD_US", period)
    return values(h)


def cycle(b: SimBoard) -> Host:
    b.power_cycle()
    return Host(b)


@pytest.fixture()
def board() -> SimBoard:
    return SimBoard(key=auth.TEST_KEY)


def test_saved_parameters_come_back_after_a_power_cycle(board: SimBoard) -> None:
    h = Host(board)
    defaults = values(h)
    assert h.ok("SAVE", op=0) == {"status": 0, "saved": 0, "differs": 1, "seq": 0}
    a = put(h, 500_000, 40, 10_000)
    assert a != defaults
    assert h.ok("SAVE", op=1) == {"status": 0, "saved": 1, "differs": 0, "seq": 1}
    h.set(0, "KP_UNM_RAD", 700_000)                       # running != saved
    assert h.ok("SAVE", op=0)["differs"] == 1
    h = cycle(board)
    assert values(h) == a and h.ok("SAVE", op=0) == {"status": 0, "saved": 1, "differs": 0, "seq": 1}
    # the loaded period is the one the control loop runs at
    t0 = board.t
    board.advance(1.0)
    assert abs((board.t - t0) - a[2] / 1e6) < 1e-9


def test_saves_alternate_sectors_and_never_touch_the_newest_copy(board: SimBoard) -> None:
    h = Host(board)
    for k in range(4):
        h.set(0, "KP_UNM_RAD", 100_000 + k)
        before = len(board.flash.log)
        assert h.ok("SAVE", op=1)["seq"] == k + 1
        writes = board.flash.log[before:]
        sectors = {addr - addr % SECTOR_BYTES for _, addr in writes}
        assert writes[0][0] == "erase" and len(sectors) == 1 and sectors <= SLOTS, writes
        if k:
            assert sectors != last, "a save wrote over the newest copy"
        last = sectors


@pytest.mark.parametrize("during", [True, False], ids=["during", "after"])
@pytest.mark.parametrize("write", range(PAGES + 1), ids=["erase"] + [f"page{k}" for k in range(PAGES)])
def test_a_power_loss_in_a_save_leaves_the_old_copy_or_the_whole_new_one(board: SimBoard, write: int,
                                                                         during: bool) -> None:
    h = Host(board)
    old = put(h, 400_000, 30, 20_000)
    h.ok("SAVE", op=1)
    new = put(h, 900_000, 60, 5_000)
    board.flash.cut(board.flash.writes + write, during)
    h.cmd("SAVE", op=1)                                   # the firmware may think it worked: the power is gone
    assert not board.flash.powered
    h = cycle(board)
    got, rep = values(h), h.ok("SAVE", op=0)
    last_write = write == PAGES and not during            # the CRC, the record's last word, is in the last page
    print(f"power lost {'during' if during else 'after'} write {write} of the save: "
          f"board starts with copy {rep['seq']} {got}")
    assert (got, rep["seq"]) == ((new, 2) if last_write else (old, 1)), (got, rep)
    assert rep["differs"] == 0


def test_a_power_loss_in_the_first_save_leaves_the_defaults(board: SimBoard) -> None:
    h = Host(board)
    defaults = values(h)
    put(h, 900_000, 60, 5_000)
    board.flash.cut(board.flash.writes + 1, during=True)
    h.cmd("SAVE", op=1)
    h = cycle(board)
    assert values(h) == defaults and h.ok("SAVE", op=0)["saved"] == 0


def test_save_is_refused_while_enabled_without_a_mac_and_with_a_dead_flash(board: SimBoard) -> None:
    h = Host(board)
    h.ok("ENABLE", mask=2, enable=1)
    assert h.cmd("SAVE", op=1)["status"] == P.STATUS["STATE"]
    h.ok("ENABLE", mask=2, enable=0)
    h.seq += 1
    board.write(P.request("SAVE", h.seq, op=1))           # no MAC: refused; the report needs none
    assert h._reply("SAVE")["status"] == P.STATUS["AUTH"]
    h.seq += 1
    board.write(P.request("SAVE", h.seq, op=0))
    assert h._reply("SAVE")["status"] == P.STATUS["OK"]
    assert h.cmd("SAVE", op=2)["status"] == P.STATUS["BAD_ARG"]
    board.flash.powered = False                            # a flash that never answers
    assert h.cmd("SAVE", op=1)["status"] == P.STATUS["STORE"]


# ---- the CLI against `torqueloop sim --flash FILE` -------------------------------------

def test_cli_save_survives_a_new_sim_process_on_the_same_flash(tmp_path, capsys, monkeypatch) -> None:
    key = tmp_path / "link.key"
    auth.write_key_file(key, auth.new_key())
    monkeypatch.setenv(auth.KEY_FILE_ENV, str(key))
    flash = tmp_path / "flash.bin"
    env = dict(os.environ)
    with sim_board("sim", "--port", "0", "--flash", str(flash), env=env) as url:
        _, _ = run(url, capsys, "set", "kp", "0.5", "--axis", "1")
        st, _ = run(url, capsys, "status")
        assert st["0"]["saved_parameters"] == {"saved": False, "differs": True, "seq": 0}
        assert "position" in st["0"] and "fault_names" in st["0"]          # the keys scripts rely on
        out, _ = run(url, capsys, "status", json_out=False)
        assert "none saved" in out
        saved, _ = run(url, capsys, "save")
        assert saved == {"saved": True, "differs": False, "seq": 1}
        run(url, capsys, "set", "kp", "0.7", "--axis", "1")
        out, _ = run(url, capsys, "status", json_out=False)
        assert "DIFFER from the saved copy 1" in out
        run(url, capsys, "enable", "--axis", "0")
        _, err = run(url, capsys, "save", rc=1)
        assert "disable" in err
        run(url, capsys, "disable", "--all")
    with sim_board("sim", "--port", "0", "--flash", str(flash), env=env) as url:   # the power cycle
        got, _ = run(url, capsys, "get", "kp", "--axis", "1")
        assert abs(got["kp"]["value"] - 0.5) < 1e-3, got
        out, _ = run(url, capsys, "status", json_out=False)
        assert "as saved on the board (copy 1)" in out
    monkeypatch.delenv(auth.KEY_FILE_ENV)
    flash.write_bytes(b"not a flash image")
    _, err = run("socket://127.0.0.1:1", capsys, "sim", "--port", "0", "--flash", str(flash), rc=1)
    assert "not a flash image" in err


def test_the_rtl_board_refuses_a_flash_file_it_would_not_use(capsys) -> None:
    _, err = run("socket://127.0.0.1:1", capsys, "sim", "--rtl", "--port", "0", "--flash", "x.bin", rc=2)
    assert "no flash model" in err
