# SPDX-License-Identifier: MIT
"""Who may drive the simulated board (the servo firmware's own C and the
plant; docs/security.md), at the byte pipe, as someone on the WLAN would
reach the RN-XV's port:

- the attack without the key - limits off, link watchdog 60 s,
  enable, ten screw turns at full command, then BOOTLOADER and an upload -
  is refused command by command, and nothing moves or changes;
- the same commands with the key, in a session, work;
- a recorded authenticated frame replayed later (in its session, after the
  link's seq was walked round, or in a new session) is refused;
- STOP and disable work without the key while the key holder's move runs;
- an upload whose MAC is not the board's key's runs the factory firmware;
- a board built without a key refuses motion and says why (NO_KEY)."""

from __future__ import annotations

import struct

import pytest

from torqueloop.sim.simboard import SimBoard
from torqueloop.spec import auth
from torqueloop.spec import bootproto as bp
from torqueloop.spec import protocol as P

KEY = auth.TEST_KEY
FACTORY = 0x51B0_0001
TURN = 8400


class Speaker:
    """Frames to the board and its replies, with or without a session."""

    def __init__(self, board: SimBoard, key: bytes | None = None) -> None:
        self.b, self.key, self.seq = board, key, 100
        self.sess: auth.Session | None = None
        self.dec = P.FrameDecoder()
        self.sent: list[bytes] = []

    def reply(self, cmd: int) -> dict:
        for _ in range(200):
            for f in self.dec.feed(self.b.read()):
                if isinstance(f, P.Frame) and f.cmd == cmd | P.REPLY_FLAG:
                    return P.decode_reply(f)
            self.b.advance(0.001)
        raise AssertionError("no reply")

    def raw(self, wire: bytes, name: str) -> int:
        self.sent.append(wire)
        self.b.write(wire)
        return self.reply(P.COMMANDS[name].cmd)["status"]

    def open(self) -> dict:
        hn = auth.new_host_nonce()
        self.b.write(P.request("SESSION", 0, host_nonce=hn))
        rep = self.reply(P.COMMANDS["SESSION"].cmd)
        if rep["status"] == P.STATUS["OK"]:
            self.sess = auth.open_session(self.key, hn, rep)
        return rep

    def __call__(self, name: str, tagged: bool | None = None, **fields) -> int:
        self.seq = (self.seq + 1) & 0xFFFF
        tag = self.sess is not None if tagged is None else tagged
        wire = self.sess.request(name, self.seq, **fields) if tag else P.request(name, self.seq, **fields)
        return self.raw(wire, name)


def param(name: str) -> int:
    return P.PARAMS[name].id


def run(b: SimBoard, seconds: float) -> None:
    end = b.t + seconds
    while b.t < end:
        b.advance(0.005)
        b.read()


def read_param(s: Speaker, name: str, axis: int = 0) -> int:
    s.seq = (s.seq + 1) & 0xFFFF
    s.b.write(P.request("GET_PARAM", s.seq, axis=P.GLOBAL_AXIS if P.PARAMS[name].scope == "global" else axis,
                        param=param(name)))
    return s.reply(P.COMMANDS["GET_PARAM"].cmd)["value"]


def status(s: Speaker, axis: int = 0) -> dict:
    s.seq = (s.seq + 1) & 0xFFFF
    s.b.write(P.request("STATUS", s.seq, axis=axis))
    return s.reply(P.COMMANDS["STATUS"].cmd)


@pytest.fixture
def board() -> SimBoard:
    return SimBoard(build_id=FACTORY, key=KEY)


def test_without_the_key_the_issues_attack_changes_nothing(board: SimBoard) -> None:
    eve = Speaker(board)                                   # a bare socket on the WLAN, no key
    before = {n: read_param(eve, n) for n in ("FOLLOW_LIMIT", "SOFT_MIN", "SOFT_MAX", "LINK_TIMEOUT_MS", "LAW")}
    x0 = board.plant.count(0)
    refused = [eve("SET_PARAM", axis=0, param=param("FOLLOW_LIMIT"), value=0x7FFF_FFFF),
               eve("SET_PARAM", axis=0, param=param("SOFT_MIN"), value=-2_147_483_647),
               eve("SET_PARAM", axis=0, param=param("SOFT_MAX"), value=0x7FFF_FFFF),
               eve("SET_PARAM", axis=P.GLOBAL_AXIS, param=param("LINK_TIMEOUT_MS"), value=60_000),
               eve("SET_PARAM", axis=0, param=param("CMD_LIMIT"), value=1023),
               eve("ENABLE", mask=1, enable=1),
               eve("MOVE", axis=0, mode=P.MOVE_UNHOMED, target=x0 + 10 * TURN),
               eve("CLEAR_FAULT", mask=3),
               eve("BOOTLOADER", magic=P.BOOTLOADER_MAGIC)]
    assert refused == [P.STATUS["AUTH"]] * len(refused)
    # a MAC made up by someone without the key, or one of another key's session
    hn = auth.new_host_nonce()
    board.write(P.request("SESSION", 0, host_nonce=hn))
    rep = eve.reply(P.COMMANDS["SESSION"].cmd)
    forged = auth.Session(bytes(32), hn, rep["board_nonce"])
    eve.seq += 1
    assert eve.raw(forged.request("ENABLE", eve.seq, mask=1, enable=1), "ENABLE") == P.STATUS["AUTH"]
    eve.seq += 1
    made_up = struct.pack("<BB", 1, 1) + bytes(auth.TAG_BYTES)
    assert eve.raw(P.encode_frame(eve.seq, P.COMMANDS["ENABLE"].cmd, made_up), "ENABLE") == P.STATUS["AUTH"]
    # an unsigned upload cannot even start: BOOTLOADER was refused, so the boot ROM never listens
    board.write(bp.encode_frame(bytes(range(200)), bytes(32)))
    run(board, 1.0)
    assert board.boot is None and not board.bootloader_requested()
    # nothing moved, nothing changed
    assert abs(board.plant.count(0) - x0) <= 2 and not board.drive(0)["on"]
    assert {n: read_param(eve, n) for n in before} == before
    st = status(eve)
    assert st["enabled"] == 0 and st["setpoint"] == st["position"]
    eve.seq += 1
    eve.b.write(P.request("COUNTERS", eve.seq))
    assert eve.reply(P.COMMANDS["COUNTERS"].cmd)["auth"] == len(refused) + 2


def test_with_the_key_the_same_commands_work_and_a_replay_is_refused(board: SimBoard) -> None:
    alice = Speaker(board, KEY)
    assert alice.open()["status"] == P.STATUS["OK"]
    x0 = board.plant.count(0)
    assert alice("SET_PARAM", axis=P.GLOBAL_AXIS, param=param("LINK_TIMEOUT_MS"), value=5000) == P.STATUS["OK"]
    assert alice("ENABLE", mask=1, enable=1) == P.STATUS["OK"]
    assert alice("MOVE", axis=0, mode=P.MOVE_UNHOMED, target=x0 + 2000) == P.STATUS["OK"]
    move = alice.sent[-1]
    run(board, 1.5)
    x1 = board.plant.count(0)
    assert x1 - x0 > 1500, "the key holder's move ran (P law: it settles a little short)"
    assert alice("MOVE", axis=0, mode=P.MOVE_UNHOMED, target=x0) == P.STATUS["OK"]
    run(board, 1.5)
    back = board.plant.count(0)
    assert abs(back - x0) < 300
    # the recorded MOVE again: REPLAY, the axis stays
    assert alice.raw(move, "MOVE") == P.STATUS["REPLAY"]
    # ... after someone without the key walked the link's seq round: still refused
    eve = Speaker(board)
    eve.seq = P.parse_packet(move.strip(b"\0")).seq
    for _ in range(3):                                       # the link's seq guard alone would now take it
        eve.seq = (eve.seq + 0x4000) & 0xFFFF
        eve.b.write(P.request("STATUS", eve.seq, axis=0))
        eve.reply(P.COMMANDS["STATUS"].cmd)
    assert alice.raw(move, "MOVE") == P.STATUS["REPLAY"]
    # ... and in a new session (the board restarted or the host reconnected): its MAC is void
    assert alice.open()["status"] == P.STATUS["OK"]
    assert alice.raw(move, "MOVE") == P.STATUS["AUTH"]
    run(board, 1.0)
    assert board.plant.count(0) < back + 50, "a replayed MOVE moved the axis"
    assert status(alice)["setpoint"] == x0


def test_stop_and_disable_need_no_key(board: SimBoard) -> None:
    alice, bob = Speaker(board, KEY), Speaker(board)          # bob: the operator's second laptop, no key
    alice.open()
    x0 = board.plant.count(0)
    alice("SET_PARAM", axis=P.GLOBAL_AXIS, param=param("LINK_TIMEOUT_MS"), value=5000)
    alice("ENABLE", mask=1, enable=1)
    alice("MOVE", axis=0, mode=P.MOVE_TRAPEZOID | P.MOVE_UNHOMED, target=x0 + 4 * TURN)     # a slow trapezoid: 4 turns at 1 turn/s
    run(board, 0.5)
    bob.seq = alice.seq
    assert bob("STOP", mask=1) == P.STATUS["OK"]
    held = board.plant.count(0)
    run(board, 1.0)
    assert abs(board.plant.count(0) - held) < 300 and board.plant.count(0) < x0 + 2 * TURN, "STOP held the axis"
    assert bob("ENABLE", mask=3, enable=0) == P.STATUS["OK"] and not board.drive(0)["on"]
    assert status(bob)["enabled"] == 0


def test_an_upload_with_a_bad_mac_runs_the_factory_firmware(board: SimBoard) -> None:
    alice = Speaker(board, KEY)
    alice.open()
    assert alice("BOOTLOADER", magic=P.BOOTLOADER_MAGIC) == P.STATUS["OK"]
    board.advance(0.001)
    assert board.read() == b"TLBW\n"
    board.write(bp.encode_frame(bytes(range(256)) * 4, bytes(32)))   # a good CRC, another key's MAC
    out = b""
    for _ in range(300):
        board.advance(0.005)
        out += board.read()
    assert out == b"TLBA\nTLBF\n"
    board.write(P.request("IDENTIFY", 0))
    assert alice.reply(P.COMMANDS["IDENTIFY"].cmd)["build_id"] == FACTORY


def test_a_board_without_a_key_refuses_motion_and_says_why() -> None:
    board = SimBoard(build_id=FACTORY, key=None)
    alice = Speaker(board, KEY)
    assert alice.open()["status"] == P.STATUS["NO_KEY"]
    x0 = board.plant.count(0)
    assert alice("ENABLE", mask=1, enable=1) == P.STATUS["NO_KEY"]
    assert alice("MOVE", axis=0, mode=P.MOVE_UNHOMED, target=x0 + TURN) == P.STATUS["NO_KEY"]
    assert alice("STOP", mask=1) == P.STATUS["OK"] and alice("ENABLE", mask=1, enable=0) == P.STATUS["OK"]
    run(board, 0.5)
    assert abs(board.plant.count(0) - x0) <= 2 and not board.drive(0)["on"]


def _nonce_after(board: SimBoard, delay_s: float, host_nonce: bytes) -> bytes:
    """Restart the firmware now, wait ``delay_s`` (less than a control period), open a session."""
    board.restart(FACTORY)
    end = board.t + delay_s
    while board.t < end:
        board.advance(end - board.t)
    board.write(P.request("SESSION", 0, host_nonce=host_nonce))
    return Speaker(board).reply(P.COMMANDS["SESSION"].cmd)["board_nonce"]


def test_the_simulated_board_draws_nonces_as_the_board_does(board: SimBoard) -> None:
    """The firmware's generator is fed the cycle counter at every byte and at
    SESSION, and starts from cleared RAM at every start.  On the simulated
    board the counter is the simulated clock, running between bytes, and
    nothing survives a restart - so what a test learns here about fresh
    nonces holds for the board."""
    hn = bytes(range(16))
    period = P.PARAMS["PERIOD_US"].default * 1e-6
    # two restarts within one control period, the same host nonce: different board nonces
    n1 = _nonce_after(board, 0.001, hn)
    n2 = _nonce_after(board, 0.001, hn)
    assert 2 * 0.001 < period and n1 != n2, "a restart within a control period repeated the nonce"
    # the counter runs between bytes: the same bytes a character later draw another nonce ...
    t0 = board.t
    late = _nonce_after(board, 0.0011, hn)
    # ... and only the moment counts, as on the board: nothing of the last run stirs the next
    fresh = SimBoard(build_id=FACTORY, key=KEY)
    while fresh.t < t0:
        fresh.advance(t0 - fresh.t)
    assert _nonce_after(fresh, 0.0011, hn) == late
    assert _nonce_after(fresh, 0.001, hn) != late
