# SPDX-License-Identifier: MIT
"""The protocol client: one command, one reply, over any :class:`Transport`.

All framing, CRC, payload layouts and codes come from the generated
:mod:`torqueloop.spec.protocol` (single definition torqueloop/spec/protocol.toml);
this module adds what a host needs on a real link:

- **seq**: on connect, IDENTIFY (accepted at any seq) tells the last seq the
  board accepted; the client continues after it.  A REPLAY answer to a first
  attempt means another host moved the seq on: resynchronise and send again.
- **retries**: no reply within ``timeout`` -> the same frame again, same seq,
  so a command whose reply was lost is not executed twice (the board answers
  REPLAY).  Then read-only commands are asked again with a fresh seq,
  SET_PARAM reads the stored value back with GET_PARAM, and other commands raise
  :class:`ReplyLost` (executed once, result unknown: look at ``status``).
- **errors a person can act on**: :class:`NoAnswer` says whether nothing at
  all came back (port, cable, RN-XV not in data mode) or bytes that were
  never a frame (baud rate, RN-XV text such as ``CMD`` or ``*HELLO*``);
  damaged chunks, CRC errors and bridge text are counted in :class:`LinkStats`.
- telemetry frames arriving between replies are queued, not lost (stamped
  with their arrival time when the transport keeps ``chunk_times``).
- **one client for every board**: the board's serial port or TCP bridge, the
  simulated board of ``torqueloop sim``, and the co-simulation's transport
  (torqueloop.sim.link), whose blocking read runs the simulated board on;
  :meth:`Client.post` and :meth:`Client.wait` pipeline commands where the
  timing matters (the co-simulated experiment's two MOVEs in one period).
- **authentication** (docs/security.md): with a key, every command that is
  not a read goes out with its MAC in a session the client opens (SESSION)
  and re-opens when the board has restarted or another host took over; the
  board's proof tells a wrong key at once (:class:`AuthFailed`).  Without a
  key, a command that needs one is not sent (:class:`KeyMissing`); STOP and
  disabling go out without a MAC when the tagged copy is refused, since
  stopping is always allowed.
"""

from __future__ import annotations

import collections
import time
from dataclasses import dataclass, field
from typing import Callable, Iterator

from torqueloop.spec import auth
from torqueloop.spec import protocol as P

from .transport import LinkInfo, Transport

#: how often one command is sent again with a fresh seq after REPLAY before the tool gives up
REPLAY_ROUNDS = 3
AUTH_STATUSES = frozenset({P.STATUS["AUTH"], P.STATUS["NO_SESSION"], P.STATUS["NO_KEY"]})
FAULT_DESC: dict[str, str] = {f["name"]: f["desc"] for f in P.SPEC["fault"]}
STATUS_DESC: dict[int, str] = {s["code"]: s["desc"] for s in P.SPEC["status"]}


class ProtocolError(Exception):
    """Base of the errors the client raises; ``str()`` is meant for a person."""


class NoAnswer(ProtocolError):
    pass


class LinkClosed(ProtocolError):
    """The link failed under us: closed by the other end (a busy RN-XV or
    simulated board refuses a second client that way) or the port went away."""


class ReplyLost(ProtocolError):
    pass


class KeyMissing(ProtocolError):
    """A command that needs the key, and the tool has none (or a bad key file)."""


def key_missing(name: str, key_error: str = "") -> KeyMissing:
    """``name`` needs the key and there is none (``key_error``: why not)."""
    why = f" ({key_error})" if key_error else ""
    return KeyMissing(f"{name} changes the machine and needs the link key{why}: name the key file with "
                      f"--key-file FILE or ${auth.KEY_FILE_ENV} (docs/security.md)")


class AuthFailed(ProtocolError):
    """The board does not accept our key: it holds another one."""


class BoardHasNoKey(ProtocolError):
    """The board was built without a key: it refuses every command that needs one."""


class CommandRejected(ProtocolError):
    """The board refused a command: ``status``, and ``why``, the rule that
    refused it (protocol.toml [[refusal]]), which the message names."""

    def __init__(self, command: str, status: int, detail: str = "", why: int = P.REFUSAL["NONE"]) -> None:
        self.command, self.status, self.why = command, status, why
        name = P.STATUS_NAME.get(status, f"status {status}")
        if why != P.REFUSAL["NONE"]:
            rule = P.REFUSAL_NAME.get(why, f"rule {why}")
            msg = f"{command} refused: {name}, {rule}: {P.REFUSAL_DESC.get(why, 'unknown rule')}"
        else:
            msg = f"{command} refused: {name} ({STATUS_DESC.get(status, 'unknown status')})"
        if name == "LOOSEN":
            msg += " - `torqueloop disable --all`, change it, enable again"
        super().__init__(msg + (f" {detail}" if detail else ""))

    @property
    def rule(self) -> str:
        """The refusal's rule by name (NONE: the board named none)."""
        return P.REFUSAL_NAME.get(self.why, "NONE")


@dataclass
class LinkStats:
    """What the host saw on the link (the board keeps its own: COUNTERS)."""

    frames_tx: int = 0
    replies: int = 0
    telemetry: int = 0
    crc_errors: int = 0          # chunks with a bad CRC (noise)
    bad_chunks: int = 0          # chunks that were no frame at all (COBS, length, oversize)
    text_bytes: int = 0          # printable bytes in bad chunks (*HELLO*, CMD ...)
    board_naks: int = 0          # error replies: the board got a damaged chunk from us
    stale_replies: int = 0       # replies to an earlier seq (after a retry)
    timeouts: int = 0
    retries: int = 0
    resyncs: int = 0
    rx_bytes: int = 0
    text_sample: bytes = field(default=b"", repr=False)


def decode_faults(mask: int) -> list[str]:
    """Fault bits to names (``FOLLOWING``) in bit order."""
    return [name for name, bit in P.FAULT.items() if mask & bit]


def describe_faults(mask: int) -> str:
    if not mask:
        return "none"
    return "; ".join(f"{n}: {FAULT_DESC[n]}" for n in decode_faults(mask))


def _printable(raw: bytes) -> int:
    return sum(32 <= b < 127 for b in raw)


class Client:
    """Protocol client.  ``clock`` and the link are injectable for tests."""

    def __init__(self, transport: Transport, info: LinkInfo | None = None, *, timeout: float = 0.5,
                 retries: int = 3, clock: Callable[[], float] = time.monotonic, key: bytes | None = None,
                 key_source: str = "", key_error: str = "") -> None:
        """``key``: the link key (None: commands that need one are refused
        here); ``key_source`` names where it came from and ``key_error`` why
        there is none, for the messages."""
        self.transport, self.info = transport, info
        self.key, self.key_source, self.key_error = key, key_source, key_error
        self.session: auth.Session | None = None
        self.timeout, self.retries = timeout, retries
        self.clock = clock
        self.stats = LinkStats()
        self._dec = P.FrameDecoder()
        self._seq = 0
        self._synced = False
        self.telemetry_queue: collections.deque[dict] = collections.deque(maxlen=100_000)
        self._posted: dict[int, P.Frame | None] = {}   # seq of a post() -> its reply, once read
        self.identity: dict[str, int] | None = None
        self.raw_tap: bytearray | None = None   # when set, every byte read is appended (upload)

    # ---- bytes in ----------------------------------------------------------
    def _closed(self, e: OSError) -> LinkClosed:
        where = self.info.url if self.info else "the link"
        if self.stats.replies == 0:
            return LinkClosed(f"{where} closed the connection before answering ({e}): the board is busy - "
                              "another client is connected (the RN-XV and `torqueloop sim` take one client "
                              "at a time); close the other session and try again")
        return LinkClosed(f"{where}: link lost after {self.stats.replies} replies ({e})")

    def _write(self, data: bytes) -> None:
        try:
            self.transport.write(data)
        except OSError as e:
            raise self._closed(e) from None

    def _read_some(self) -> bytes:
        try:
            n = getattr(self.transport, "in_waiting", 0) or 0
            data = self.transport.read(max(1, min(n, 4096)))
            if data:
                more = getattr(self.transport, "in_waiting", 0) or 0
                if more:
                    data += self.transport.read(min(more, 4096))
        except OSError as e:
            raise self._closed(e) from None
        self.stats.rx_bytes += len(data)
        if self.raw_tap is not None:
            self.raw_tap += data
        return data

    def _frames(self, data: bytes) -> Iterator[P.Frame]:
        # Run the decoder over all of ``data`` first: FrameDecoder.feed is a generator
        # that clears its buffer only after the consumer resumes it, and _exchange
        # stops consuming at its reply.
        times = getattr(self.transport, "chunk_times", None)
        for item in list(self._dec.feed(data)):
            at = times.popleft() if times else None   # one chunk, one item
            if isinstance(item, P.FrameError):
                if item.status == P.STATUS["CRC"]:
                    self.stats.crc_errors += 1
                else:
                    self.stats.bad_chunks += 1
                t = _printable(item.raw)
                self.stats.text_bytes += t
                if t and len(self.stats.text_sample) < 64:
                    self.stats.text_sample += item.raw[:64]
                continue
            if item.cmd == P.TELEMETRY_CMD:
                self.stats.telemetry += 1
                try:
                    rec = P.decode_telemetry(item)
                except Exception:   # a CRC-valid frame of the wrong length: count, do not die
                    self.stats.bad_chunks += 1
                    continue
                if at is not None:
                    rec["rx_time"] = at
                self.telemetry_queue.append(rec)
                continue
            if item.seq in self._posted and item.cmd & P.REPLY_FLAG:
                self._posted[item.seq] = item      # the reply a wait() collects
                continue
            yield item

    def poll(self) -> None:
        """Read what has arrived, without waiting (telemetry, replies to posts)."""
        while getattr(self.transport, "in_waiting", 0):
            for f in self._frames(self._read_some()):
                self.stats.stale_replies += 1

    def post(self, name: str, **fields: int) -> int:
        """Send a command without waiting for its reply (no retry): returns its
        seq for :meth:`wait`.  With a session, it carries its MAC as in :meth:`transact`."""
        if auth.needs_key(name, fields) and self.key is None:
            raise self._key_missing(name)
        if not self._synced:
            self.connect()
        tagged = self.session is not None and not P.COMMANDS[name].untagged
        seq = self._next_seq()
        self._write(self.session.request(name, seq, **fields) if tagged else P.request(name, seq, **fields))
        self.stats.frames_tx += 1
        self._posted[seq] = None
        return seq

    def wait(self, seq: int) -> dict[str, int]:
        """The reply to the command :meth:`post` sent with ``seq`` (status
        included: the caller judges it); :class:`NoAnswer` after ``timeout``."""
        deadline = self.clock() + self.timeout
        while self._posted.get(seq) is None and self.clock() < deadline:
            for f in self._frames(self._read_some()):
                self.stats.stale_replies += 1
        f = self._posted.pop(seq, None)
        if f is None:
            self.stats.timeouts += 1
            raise NoAnswer(self._no_answer_hint(f"seq {seq}"))
        self.stats.replies += 1
        return P.decode_reply(f)

    def pump(self, duration: float) -> None:
        """Read for ``duration`` seconds, queueing telemetry."""
        end = self.clock() + duration
        while self.clock() < end:
            for f in self._frames(self._read_some()):
                self.stats.stale_replies += 1

    # ---- one transaction -----------------------------------------------------
    def _next_seq(self) -> int:
        self._seq = (self._seq + 1) & 0xFFFF
        self._posted.pop(self._seq, None)   # a post nobody waited for, 65536 commands ago
        return self._seq

    def _exchange(self, name: str, seq: int, fields: dict, session: auth.Session | None = None
                  ) -> tuple[dict, int]:
        """Send with retries (with its MAC in ``session``); returns (decoded reply, attempt that got it)."""
        c = P.COMMANDS[name]
        wire = session.request(name, seq, **fields) if session else P.request(name, seq, **fields)
        want = c.cmd | P.REPLY_FLAG
        for attempt in range(self.retries + 1):
            if attempt:
                self.stats.retries += 1
            self._write(wire)
            self.stats.frames_tx += 1
            deadline = self.clock() + self.timeout
            resend = False
            while not resend and self.clock() < deadline:
                for f in self._frames(self._read_some()):
                    if f.cmd == P.ERROR_CMD:
                        # Something we sent (or text the bridge inserted) arrived
                        # damaged; our frame may be the one: send it again now.
                        self.stats.board_naks += 1
                        resend = attempt < self.retries
                    elif f.cmd == want and f.seq == seq:
                        self.stats.replies += 1
                        return P.decode_reply(f), attempt
                    else:
                        self.stats.stale_replies += 1
            if not resend:
                self.stats.timeouts += 1
        raise NoAnswer(self._no_answer_hint(name))

    def _no_answer_hint(self, name: str) -> str:
        s = self.stats
        where = f" from {self.info.url}" if self.info else ""
        msg = f"no answer to {name}{where} after {self.retries + 1} tries of {self.timeout:g} s."
        kind = self.info.kind if self.info else "other"
        if s.rx_bytes == 0:
            if kind == "tcp":
                return (msg + " Nothing came back at all: the TCP connection is open but the board is silent. "
                        "Check that the RN-XV is in data mode (after `$$$` configuration it needs `exit`), "
                        "that its UART baud rate equals the firmware's (115200 by default: `set uart baud "
                        "115200`, `save`, `reboot`), that its TX/RX go to the FPGA header pins of docs/hardware.md, "
                        "and that the FPGA is configured and running the servo firmware.")
            return (msg + " Nothing came back at all: check the port name, that TX and RX are crossed "
                    "(adapter TX -> FPGA RX), the common ground, 3.3 V levels, and that the FPGA is "
                    "configured and running the servo firmware.")
        text = s.text_sample.decode("ascii", "replace")
        if b"CMD" in s.text_sample:
            return msg + f" The RN-XV is in command mode (it said {text!r}): send `exit` then reconnect."
        return (msg + f" {s.rx_bytes} bytes arrived but {s.replies} valid replies ({s.crc_errors} CRC errors, "
                f"{s.bad_chunks} chunks that were no frame, text seen: {text!r}). Most likely a baud-rate "
                f"mismatch (this end: {self.info.baud if self.info else '?'} baud; firmware default 115200) "
                "or an RN-XV that inserts text (`set comm remote 0`, `set comm open 0`, `set comm close 0`).")

    # ---- authentication ------------------------------------------------------
    def _key_missing(self, name: str) -> KeyMissing:
        return key_missing(name, self.key_error)

    def _board_has_no_key(self, name: str) -> BoardHasNoKey:
        return BoardHasNoKey(f"{name} refused: the board has no link key, so it refuses every command that "
                             "changes the machine and every upload; reading, stop and disable still work. "
                             "Provision the key into its boot ROM: docs/security.md, 'Key provisioning'")

    def _auth_failed(self) -> AuthFailed:
        src = f" from {self.key_source}" if self.key_source else ""
        return AuthFailed(f"authentication failed: the board does not accept the key{src} (key id "
                          f"{auth.key_id(self.key or b'')}): it was provisioned with another key")

    def open_session(self, host_nonce: bytes | None = None) -> auth.Session:
        """SESSION: a fresh challenge from the board, whose proof shows it holds our key.
        ``host_nonce``: a fixed one for runs that must repeat byte for byte (a
        simulation); a fresh random one otherwise, as a real host must."""
        if self.key is None:
            raise self._key_missing("SESSION")
        if not self._synced:
            self.connect()
        hn = auth.new_host_nonce() if host_nonce is None else host_nonce
        rep, _ = self._exchange("SESSION", self._next_seq(), {"host_nonce": hn})
        if rep["status"] == P.STATUS["NO_KEY"]:
            raise self._board_has_no_key("SESSION")
        if rep["status"] != P.STATUS["OK"]:
            raise CommandRejected("SESSION", rep["status"])
        try:
            self.session = auth.open_session(self.key, hn, rep)
        except auth.AuthError:
            self.session = None
            raise self._auth_failed() from None
        return self.session

    def transact(self, name: str, **fields: int) -> dict[str, int]:
        """Run one command; returns the reply fields (status OK) or raises."""
        needs = auth.needs_key(name, fields)
        if needs and self.key is None:
            raise self._key_missing(name)              # refused here: nothing is sent
        if not self._synced and name != "IDENTIFY":
            self.connect()
        if self.key is None or P.COMMANDS[name].untagged:   # here only commands that need no key
            return self._transact(name, fields, None)
        try:
            return self._authenticated(name, fields)
        except (AuthFailed, BoardHasNoKey, CommandRejected) as e:
            if needs or (isinstance(e, CommandRejected) and e.status not in AUTH_STATUSES):
                raise
            return self._transact(name, fields, None)    # stopping is always allowed: without a MAC

    def _authenticated(self, name: str, fields: dict) -> dict[str, int]:
        """The command with its MAC.  The session is opened again once if the
        board asks (it restarted, another host opened one, this one is used
        up); the new session's proof tells a wrong key from a stale session."""
        for attempt in range(2):
            if self.session is None or attempt:
                self.open_session()
            try:
                return self._transact(name, fields, self.session)
            except CommandRejected as e:
                if e.status == P.STATUS["NO_KEY"]:
                    raise self._board_has_no_key(name) from None
                if e.status not in (P.STATUS["NO_SESSION"], P.STATUS["AUTH"]) or attempt:
                    if e.status == P.STATUS["AUTH"]:
                        # The session was opened just now and the board's proof showed it
                        # holds our key: the key is right, another SESSION ended ours.
                        raise CommandRejected(name, e.status, "- twice, although the board proved it holds "
                                              "this key: another host opened a session on the board in "
                                              "between (someone else is on the link; docs/security.md)"
                                              ) from None
                    raise
        raise AssertionError("unreachable")

    def _transact(self, name: str, fields: dict, session: auth.Session | None) -> dict[str, int]:
        """One command with a fresh seq.  REPLAY to a first copy means it did
        not run (the board's seq was moved on: another host, or frames
        injected into the link): resynchronise and send it again, at most
        REPLAY_ROUNDS times.  REPLAY to a retransmission means the first copy
        may have run and only its reply was lost: a read is asked again (as
        often as ``retries``), anything else is not."""
        refused = lost = 0
        while True:
            seq = self._next_seq()
            rep, attempt = self._exchange(name, seq, fields, session)
            st = rep["status"]
            if st != P.STATUS["REPLAY"]:
                if st != P.STATUS["OK"]:
                    raise CommandRejected(name, st, why=rep["why"])
                return rep
            if attempt == 0:
                refused += 1
                if refused >= REPLAY_ROUNDS:
                    raise CommandRejected(name, st, f"- refused as a replay {refused} times, so it did not run: "
                                          "something else on the link keeps moving the board's sequence number "
                                          "ahead (another host, or frames injected into this link; docs/security.md)")
                self.stats.resyncs += 1
                self.connect()
                continue
            if P.COMMANDS[name].repeatable:
                lost += 1
                if lost > self.retries:
                    raise ReplyLost(f"{name}: the replies of {lost} tries were lost (each retry answered as a "
                                    "replay); the link loses too much - check it and try again")
                continue                       # harmless to ask again with a fresh seq
            if name == "SET_PARAM":
                got = self._transact("GET_PARAM", {"axis": fields["axis"], "param": fields["param"]}, None)
                return {"status": 0, "value": got["value"]}
            raise ReplyLost(f"{name} (seq {seq}) reached the board but its reply was lost; "
                            "it ran at most once - check `torqueloop status` before repeating it")

    # ---- commands ---------------------------------------------------------------
    def connect(self) -> dict[str, int]:
        """IDENTIFY and continue after the board's last accepted seq."""
        self._seq = (self._seq + 1) & 0xFFFF
        rep, _ = self._exchange("IDENTIFY", self._seq, {})
        if rep["status"] != P.STATUS["OK"]:
            raise CommandRejected("IDENTIFY", rep["status"])
        if rep["proto_version"] != P.PROTO_VERSION:
            raise ProtocolError(f"board speaks protocol version {rep['proto_version']}, this tool "
                                f"{P.PROTO_VERSION}: update the tool or the firmware")
        self._seq = rep["last_seq"]
        self._synced = True
        self.identity = rep
        return rep

    def identify(self) -> dict[str, int]:
        return self.connect()

    def get_param(self, name: str, axis: int = 0) -> int:
        p = P.PARAMS[name]
        ax = P.GLOBAL_AXIS if p.scope == "global" else axis
        return self.transact("GET_PARAM", axis=ax, param=p.id)["value"]

    def set_param(self, name: str, value: int, axis: int = 0) -> int:
        p = P.PARAMS[name]
        if not p.min <= value <= p.max:
            raise CommandRejected("SET_PARAM", P.STATUS["RANGE"], f"({name} = {value} is outside [{p.min}, {p.max}]; "
                                  "checked before sending)", why=P.REFUSAL["BELOW_MIN" if value < p.min else "ABOVE_MAX"])
        ax = P.GLOBAL_AXIS if p.scope == "global" else axis
        return self.transact("SET_PARAM", axis=ax, param=p.id, value=value)["value"]

    def enable(self, mask: int, on: bool = True) -> None:
        try:
            self.transact("ENABLE", mask=mask, enable=int(on))
        except CommandRejected as e:
            if e.why == P.REFUSAL["FAULT"]:
                faults = [self.status(a)["faults"] for a in range(P.AXIS_COUNT) if mask & (1 << a)]
                detail = "; ".join(f"axis {a}: {describe_faults(f)}"
                                   for a, f in zip([a for a in range(P.AXIS_COUNT) if mask & (1 << a)], faults))
                raise CommandRejected("ENABLE", e.status, why=e.why, detail=f"- latched faults: {detail} "
                                      "(remove the cause, then `torqueloop clear-fault`)") from None
            raise

    def move(self, axis: int, target_counts: int, trapezoid: bool = False, unhomed: bool = False) -> None:
        mode = (P.MOVE_TRAPEZOID if trapezoid else 0) | (P.MOVE_UNHOMED if unhomed else 0)
        self.transact("MOVE", axis=axis, mode=mode, target=target_counts)

    def drive(self, axis: int, duty: int) -> None:
        """DRIVE: open-loop command ``duty`` (signed PWM steps) on an enabled axis."""
        self.transact("DRIVE", axis=axis, duty=duty)

    def home(self, axis: int, mode: str, index: bool = False) -> None:
        self.transact("HOME", axis=axis, mode=P.HOME_MODES[mode], index=int(index))

    def heartbeat(self) -> None:
        """Feed the board's link watchdog: only commands that show the host in
        control do (ENABLE, MOVE, STOP, HOME, HEARTBEAT); polls do not."""
        self.transact("HEARTBEAT")

    def stop(self, mask: int) -> None:
        self.transact("STOP", mask=mask)

    def status(self, axis: int = 0) -> dict[str, int]:
        return self.transact("STATUS", axis=axis)

    def clear_fault(self, mask: int) -> tuple[int, int]:
        r = self.transact("CLEAR_FAULT", mask=mask)
        return r["faults0"], r["faults1"]

    def counters(self) -> dict[str, int]:
        return self.transact("COUNTERS")

    def set_telemetry(self, every: int) -> None:
        self.transact("TELEMETRY", every=every)

    def save(self) -> dict[str, int]:
        """Store the running parameters on the board (every axis disabled); the store's report."""
        return self.transact("SAVE", op=1)

    def store_report(self) -> dict[str, int] | None:
        """saved (a copy is stored), differs (the running parameters are not it), seq;
        None from a firmware without the parameter store."""
        try:
            return self.transact("SAVE", op=0)
        except CommandRejected as e:
            if e.status == P.STATUS["UNKNOWN_CMD"]:
                return None
            raise

    def bootloader(self) -> None:
        self.transact("BOOTLOADER", magic=P.BOOTLOADER_MAGIC)

    def take_telemetry(self) -> list[dict]:
        out = list(self.telemetry_queue)
        self.telemetry_queue.clear()
        return out

    def close(self) -> None:
        self.transport.close()
