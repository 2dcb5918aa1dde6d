# SPDX-License-Identifier: MIT
"""The host tool's protocol client against scripted fake links: timeouts,
retries, lost and damaged frames, RN-XV text (``*HELLO*``, ``CMD``), seq
resynchronisation, telemetry between replies, authentication (a wrong key,
no key, a board without a key, a session the board lost, stopping without
a key), and a seeded random lossy channel around the real servo firmware
(the simulated board's C) checking that no command is ever executed twice.

The scripted board follows docs/protocol.md's rules (seq window, REPLAY
without executing, error replies to damaged chunks, SESSION and the MAC of
commands that need the key), written here from the document with hmac
directly, not from the firmware."""

from __future__ import annotations

import hashlib
import hmac
import os
import random
import struct

import pytest

from torqueloop.spec import auth
from torqueloop.spec import protocol as P
from torqueloop.host.client import (AuthFailed, BoardHasNoKey, Client, CommandRejected, KeyMissing, NoAnswer,
                                    ReplyLost)
from torqueloop.host.transport import LinkInfo

KEY = bytes(range(100, 132))


class FakeClock:
    def __init__(self) -> None:
        self.t = 0.0

    def __call__(self) -> float:
        return self.t


class DocBoard:
    """A board as docs/protocol.md describes it, minimal: STATUS, SET/GET of one
    parameter, MOVE counted, TELEMETRY on request."""

    def __init__(self, last_seq: int = 0, any_seq: bool = False, key: bytes | None = KEY) -> None:
        self.last, self.any = last_seq, any_seq
        self.moves: list[int] = []
        self.kp = 17132
        self.dec = P.FrameDecoder()
        self.key = key
        self.nonces: tuple[bytes, bytes] | None = None    # (host, board) of the open session
        self.auth_seqs: list[int] = []                     # authenticated seqs of this session
        self.enabled = True

    def _tag_ok(self, f: P.Frame) -> bool:
        """docs/security.md: HMAC-SHA-256(key, 'TLCF' | board nonce | host nonce | seq cmd len | payload)[:16]."""
        hn, bn = self.nonces
        mac = hmac.new(self.key, b"TLCF" + bn + hn + struct.pack("<HBB", f.seq, f.cmd, len(f.payload))
                       + f.payload[:-16], hashlib.sha256).digest()[:16]
        return hmac.compare_digest(mac, f.payload[-16:])

    def _auth(self, c: P.Command, f: P.Frame, tagged: bool, args: dict) -> int | None:
        """The status that refuses the frame, or None if it may run."""
        needs = c.auth == "key" and not any(args.get(k) == v for k, v in c.open_when.items())
        if not tagged:
            return (P.STATUS["NO_KEY"] if self.key is None else P.STATUS["AUTH"]) if needs else None
        if self.key is None:
            return P.STATUS["NO_KEY"]
        if self.nonces is None:
            return P.STATUS["NO_SESSION"]
        if self.auth_seqs:
            off = (f.seq - self.auth_seqs[0]) & 0xFFFF
            if off >= auth.SESSION_WINDOW:
                return P.STATUS["NO_SESSION"]
            if off <= (self.auth_seqs[-1] - self.auth_seqs[0]) & 0xFFFF:
                return P.STATUS["REPLAY"]
        if not self._tag_ok(f):
            return P.STATUS["AUTH"]
        self.auth_seqs.append(f.seq)
        return None

    def _new(self, seq: int) -> bool:
        return not self.any or 0 < ((seq - self.last) & 0xFFFF) < P.SEQ_WINDOW

    def receive(self, data: bytes) -> bytes:
        out = b""
        for f in self.dec.feed(data):
            if isinstance(f, P.FrameError):
                out += P.encode_frame(0, P.ERROR_CMD, bytes([f.status]))
                continue
            c = P.BY_CMD[f.cmd]
            rc = f.cmd | P.REPLY_FLAG
            n = struct.calcsize(c.req_fmt)
            tagged = len(f.payload) == n + auth.TAG_BYTES
            args = dict(zip((n for n, _ in c.req), struct.unpack(c.req_fmt, f.payload[:n])))
            if not tagged and (st := self._auth(c, f, False, args)) is not None:
                out += P.encode_frame(f.seq, rc, bytes([st]))
                continue
            if c.name not in ("IDENTIFY", "SESSION"):
                if not self._new(f.seq):
                    out += P.encode_frame(f.seq, rc, bytes([P.STATUS["REPLAY"]]))
                    continue
            if tagged and (st := self._auth(c, f, True, args)) is not None:
                out += P.encode_frame(f.seq, rc, bytes([st]))
                continue
            if c.name not in ("IDENTIFY", "SESSION"):
                self.last, self.any = f.seq, True
            if c.name == "SESSION":
                if self.key is None:
                    out += P.encode_frame(f.seq, rc, bytes([P.STATUS["NO_KEY"]]))
                    continue
                bn = os.urandom(16)
                self.nonces, self.auth_seqs = (args["host_nonce"], bn), []
                rep = b"\x00" + bn + hmac.new(self.key, b"TLSP" + args["host_nonce"] + bn, hashlib.sha256).digest()[:16]
            elif c.name == "ENABLE":
                self.enabled = bool(args["enable"])
                rep = b"\x00"
            elif c.name == "IDENTIFY":
                rep = struct.pack(c.rep_fmt, 0, P.PROTO_VERSION, 0x100, 0xB11D, 2, self.last, 50_000_000)
            elif c.name == "STATUS":
                vals = {"enabled": 1, "home": 2, "position": 1234, "setpoint": 1234}
                rep = struct.pack(c.rep_fmt, *(vals.get(n, 0) for n, _ in c.rep))
            elif c.name == "MOVE":
                self.moves.append(args["target"])
                rep = b"\x00"
            elif c.name == "SET_PARAM":
                self.kp = args["value"]
                rep = struct.pack(c.rep_fmt, 0, self.kp)
            elif c.name == "GET_PARAM":
                rep = struct.pack(c.rep_fmt, 0, self.kp)
            else:
                rep = b"\x00"
            out += P.encode_frame(f.seq, rc, rep)
        return out


class FakeSerial:
    """The serial-port side both fake links share: ``pending`` bytes to read;
    an empty read advances the fake clock by the poll interval."""

    pending: bytes
    clock: FakeClock
    timeout: float

    @property
    def in_waiting(self) -> int:
        return len(self.pending)

    def read(self, size: int = 1) -> bytes:
        if not self.pending:
            self.clock.t += self.timeout
            return b""
        out, self.pending = self.pending[:size], self.pending[size:]
        return out

    def close(self) -> None:
        pass


class ScriptedLink(FakeSerial):
    """Each write goes through ``script`` (one action per written frame, then
    'ok'): ok, drop_request, drop_reply, corrupt_request, corrupt_reply,
    hello (``*HELLO*`` before the reply).  Reads return what is pending;
    an empty read advances the fake clock by the poll interval."""

    def __init__(self, board: DocBoard | None, clock: FakeClock, script: list[str] | None = None) -> None:
        self.board, self.clock = board, clock
        self.script = list(script or [])
        self.pending = b""
        self.writes: list[bytes] = []
        self.timeout = 0.05
        self.silent_bytes = b""

    def write(self, data: bytes) -> int:
        self.writes.append(data)
        act = self.script.pop(0) if self.script else "ok"
        if self.board is None:
            self.pending += self.silent_bytes
            return len(data)
        if act == "drop_request":
            return len(data)
        if act == "corrupt_request":
            b = bytearray(data)
            b[len(b) // 2] ^= 0x10
            data = bytes(b)
        rep = self.board.receive(data)
        if act == "drop_reply":
            rep = b""
        elif act == "corrupt_reply":
            b = bytearray(rep)
            b[4] ^= 0x01
            rep = bytes(b)
        elif act == "hello":
            rep = b"*HELLO*" + rep
        self.pending += rep
        return len(data)



def make(script: list[str] | None = None, board: DocBoard | None = None, kind: str = "tcp",
         key: bytes | None = KEY):
    clock = FakeClock()
    board = board if board is not None else DocBoard()
    link = ScriptedLink(board, clock, script)
    c = Client(link, LinkInfo("socket://fake:2000", kind, 115200), timeout=0.5, retries=3, clock=clock, key=key,
               key_source="test.key")
    return c, link, board, clock


def test_silent_link_times_out_with_a_hint_for_the_rnxv() -> None:
    clock = FakeClock()
    link = ScriptedLink(None, clock)
    c = Client(link, LinkInfo("socket://fake:2000", "tcp", 115200), timeout=0.5, retries=2, clock=clock)
    with pytest.raises(NoAnswer) as e:
        c.connect()
    assert len(link.writes) == 3                 # first try + 2 retries
    assert clock.t == pytest.approx(1.5, abs=0.06)
    assert "data mode" in str(e.value) and "Nothing came back" in str(e.value)
    assert c.stats.timeouts == 3


def test_serial_garbage_points_at_the_baud_rate() -> None:
    clock = FakeClock()
    link = ScriptedLink(None, clock)
    rng = random.Random(5)
    link.silent_bytes = bytes(rng.randrange(256) for _ in range(40)) + b"\x00"   # wrong-baud noise
    c = Client(link, LinkInfo("/dev/ttyUSB0", "serial", 9600), timeout=0.2, retries=1, clock=clock)
    with pytest.raises(NoAnswer) as e:
        c.connect()
    assert "baud" in str(e.value) and "9600" in str(e.value)
    assert c.stats.rx_bytes > 0 and c.stats.replies == 0
    assert c.stats.crc_errors + c.stats.bad_chunks >= 1


def test_rnxv_command_mode_is_recognised() -> None:
    clock = FakeClock()
    link = ScriptedLink(None, clock)
    link.silent_bytes = b"CMD\r\n"
    c = Client(link, LinkInfo("socket://fake:2000", "tcp", 115200), timeout=0.2, retries=0, clock=clock)
    link.silent_bytes += b"\x00"
    with pytest.raises(NoAnswer) as e:
        c.connect()
    assert "command mode" in str(e.value) and "exit" in str(e.value)


def test_hello_text_before_a_reply_is_counted_and_skipped() -> None:
    c, link, board, _ = make(["hello", "hello"])
    rep = c.connect()
    assert rep["build_id"] == 0xB11D
    assert c.status(0)["position"] == 1234
    assert c.stats.text_bytes >= 14 and c.stats.bad_chunks == 2
    assert c.stats.retries == 0 and len(link.writes) == 2


def test_lost_reply_of_a_move_is_not_executed_twice() -> None:
    # the MOVE reaches the board, its reply is lost; the retry (same seq) gets REPLAY
    c, link, board, _ = make(["ok", "ok", "drop_reply", "ok"])    # IDENTIFY, SESSION, MOVE, its retry
    c.connect()
    with pytest.raises(ReplyLost) as e:
        c.move(0, 4200)
    assert board.moves == [4200]
    assert "status" in str(e.value)
    assert link.writes[2] == link.writes[3]           # the retry is byte-identical: same seq and MAC


def test_lost_request_is_resent_and_executed_once() -> None:
    c, link, board, _ = make(["ok", "ok", "drop_request"])
    c.connect()
    c.move(0, -100)
    assert board.moves == [-100]
    assert c.stats.retries == 1 and c.stats.timeouts == 1


def test_lost_reply_of_a_read_is_asked_again_with_a_new_seq() -> None:
    c, link, board, _ = make(["ok", "drop_reply"])
    c.connect()
    assert c.status(0)["position"] == 1234
    seqs = [P.parse_packet(w.strip(b"\x00")).seq for w in link.writes]
    assert seqs[1] == seqs[2] and seqs[3] == seqs[2] + 1


def test_lost_reply_of_a_set_is_read_back() -> None:
    c, link, board, _ = make(["ok", "ok", "drop_reply"])
    c.connect()
    assert c.set_param("KP_Q16", 4321) == 4321
    assert board.kp == 4321


def test_damaged_reply_counts_a_crc_error_and_retries() -> None:
    c, link, board, _ = make(["ok", "corrupt_reply"])
    c.connect()
    assert c.status(0)["setpoint"] == 1234
    assert c.stats.crc_errors == 1


def test_damaged_request_gets_an_error_reply_and_is_resent_at_once() -> None:
    c, link, board, clock = make(["ok", "ok", "corrupt_request"])
    c.connect()
    t0 = clock.t
    c.move(1, 77)
    assert board.moves == [77]
    assert c.stats.board_naks == 1
    assert clock.t - t0 < 0.2        # no wait for the timeout


def test_another_host_moved_the_seq_on_and_the_client_resyncs() -> None:
    board = DocBoard()
    c, link, _, _ = make([], board)
    c.connect()
    board.last, board.any = (board.last + 500) & 0xFFFF, True   # another host sent 500 commands
    c.move(0, 5)
    assert board.moves == [5] and c.stats.resyncs == 1


def test_refusals_are_named() -> None:
    class Refuser(DocBoard):
        def receive(self, data: bytes) -> bytes:
            out = b""
            for f in self.dec.feed(data):
                if isinstance(f, P.Frame) and f.cmd == P.COMMANDS["MOVE"].cmd:
                    out += P.encode_frame(f.seq, f.cmd | P.REPLY_FLAG, bytes([P.STATUS["STATE"]]))
                elif isinstance(f, P.Frame):
                    self.dec = P.FrameDecoder()
                    return DocBoard.receive(self, data)
            return out

    c, *_ = make([], Refuser(), key=None)
    c.connect()
    c.key = KEY         # past the client's own check: the board's refusal is what is named here
    with pytest.raises(CommandRejected) as e:
        c.move(0, 1)
    assert "STATE" in str(e.value) and "disabled" in str(e.value)


# ---- authentication ---------------------------------------------------------------

def test_with_the_key_commands_carry_a_mac_and_reads_do_not() -> None:
    c, link, board, _ = make()
    c.connect()
    c.move(0, 10)
    c.status(0)
    c.stop(1)
    cmds = [P.parse_packet(w.strip(b"\x00")) for w in link.writes]
    assert [(P.BY_CMD[f.cmd].name, len(f.payload)) for f in cmds] == [
        ("IDENTIFY", 0), ("SESSION", 16), ("MOVE", 6 + 16), ("STATUS", 1), ("STOP", 1 + 16)]
    assert board.moves == [10] and len(board.auth_seqs) == 2


def test_a_wrong_key_says_authentication_failed_at_once() -> None:
    c, link, board, clock = make(key=bytes(32))
    c.connect()
    with pytest.raises(AuthFailed, match="authentication failed.*test.key.*key id") as e:
        c.move(0, 10)
    assert "another key" in str(e.value) and clock.t < 0.2    # from the board's proof: no timeout
    assert board.moves == [] and c.stats.timeouts == 0


def test_no_key_sends_nothing_that_needs_one() -> None:
    c, link, board, _ = make(key=None)
    c.connect()
    n = len(link.writes)
    for call in (lambda: c.move(0, 10), lambda: c.enable(1), lambda: c.set_param("KP_Q16", 5),
                 lambda: c.clear_fault(1), c.bootloader):
        with pytest.raises(KeyMissing, match="needs the link key.*--key-file.*TORQUELOOP_KEY_FILE"):
            call()
    assert len(link.writes) == n and board.moves == []
    # stopping is always allowed: STOP and disable go without a MAC, reads work
    c.stop(3)
    c.enable(3, False)
    assert not board.enabled and c.status(0)["position"] == 1234


def test_a_board_without_a_key_is_named() -> None:
    c, link, board, _ = make(board=DocBoard(key=None))
    c.connect()
    with pytest.raises(BoardHasNoKey, match="board has no link key.*Key provisioning"):
        c.move(0, 10)
    c.enable(3, False)                                  # the untagged copy: disabling works
    assert not board.enabled and board.moves == []


def test_a_lost_session_is_opened_again_and_stopping_survives_a_wrong_key() -> None:
    c, link, board, _ = make()
    c.connect()
    c.move(0, 1)
    board.nonces = None                                 # the board restarted (or another host took over)
    c.move(0, 2)
    assert board.moves == [1, 2] and sum(P.parse_packet(w.strip(b"\x00")).cmd == P.COMMANDS["SESSION"].cmd
                                         for w in link.writes) == 2
    # another host opened its own session: our MAC no longer verifies, a new session fixes it
    board.nonces = (bytes(16), bytes(16))
    c.move(0, 3)
    assert board.moves == [1, 2, 3]
    # a host whose key is wrong can still stop and disable
    w, _, board2, _ = make(key=bytes(32))
    w.connect()
    w.stop(1)
    w.enable(1, False)
    assert not board2.enabled


def test_client_checks_ranges_before_sending() -> None:
    c, link, *_ = make()
    c.connect()
    n = len(link.writes)
    with pytest.raises(CommandRejected):
        c.set_param("CMD_LIMIT", 5000)
    assert len(link.writes) == n


def test_telemetry_between_replies_is_queued() -> None:
    c, link, board, _ = make()
    c.connect()
    payload = bytes(P.telemetry_payload_bytes())
    link.pending += P.encode_frame(7, P.TELEMETRY_CMD, payload) * 3
    c.status(0)
    assert len(c.take_telemetry()) == 3 and c.stats.telemetry == 3


# ---- random lossy channel around the real firmware ------------------------------

class LossyLink(FakeSerial):
    """Drops, flips bits in, or injects text into whole frames, both directions,
    in front of the simulated board's firmware (no simulated time passes)."""

    def __init__(self, board, rng: random.Random, clock: FakeClock, p: float) -> None:
        self.board, self.rng, self.clock, self.p = board, rng, clock, p
        self.pending = b""
        self.timeout = 0.05
        self.delivered: list[tuple[int, int]] = []   # (seq, cmd) of every intact frame the board got

    def _mangle(self, data: bytes) -> bytes:
        r = self.rng.random()
        if r < self.p:
            return b""
        if r < 2 * self.p:
            b = bytearray(data)
            b[self.rng.randrange(len(b))] ^= 1 << self.rng.randrange(8)
            return bytes(b)
        if r < 2.5 * self.p:
            return b"*HELLO*" + data
        return data

    def write(self, data: bytes) -> int:
        sent = self._mangle(data)
        if sent.endswith(data):
            f = P.parse_packet(data.strip(b"\x00"))
            self.delivered.append((f.seq, f.cmd))
        self.board.write(sent)
        out = self.board.read()
        self.pending += self._mangle(out) if out else b""
        return len(data)



def test_random_lossy_link_never_runs_a_command_twice() -> None:
    from torqueloop.sim.simboard import SimBoard

    seed = int(os.environ.get("TL_SEED", random.randrange(1, 2**32)))
    print(f"seed {seed} (rerun with TL_SEED={seed})")
    rng = random.Random(seed)
    board = SimBoard(key=KEY)
    clock = FakeClock()
    c = Client(LossyLink(board, rng, clock, 0.08), LinkInfo("loop://", "other", 115200),
               timeout=0.3, retries=8, clock=clock, key=KEY)
    c.connect()
    link = c.transport
    value = c.get_param("FOLLOW_LIMIT", 0)
    for k in range(60):
        value += 1
        assert c.set_param("FOLLOW_LIMIT", value, 0) == value, f"seed {seed}, step {k}"
        if k % 10 == 0:
            c.status(1)
    assert c.get_param("FOLLOW_LIMIT", 0) == value, f"seed {seed}"
    cnt = c.counters()
    # Exactly once: the board executed (frames_ok) every IDENTIFY and SESSION copy it got
    # (both answer any seq) plus one per distinct seq, and answered every other copy of a
    # seq with REPLAY.
    any_seq = {P.COMMANDS["IDENTIFY"].cmd, P.COMMANDS["SESSION"].cmd}
    others = [d for d in link.delivered if d[1] not in any_seq]
    expect_ok = len(link.delivered) - len(others) + len(set(others))
    assert cnt["frames_ok"] == expect_ok, f"seed {seed}: {cnt} vs {expect_ok}"
    assert cnt["replay"] == len(others) - len(set(others)), f"seed {seed}"
    # ... and the client used one seq per SET it was asked for: 60 SETs ran, not more
    set_cmd = P.COMMANDS["SET_PARAM"].cmd
    assert len({d for d in others if d[1] == set_cmd}) == 60, f"seed {seed}"
    # the channel really was lossy, and the board noticed the damage
    assert c.stats.retries > 0 and cnt["crc"] + cnt["framing"] > 0, f"seed {seed}"
