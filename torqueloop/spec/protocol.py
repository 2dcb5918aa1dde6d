# SPDX-License-Identifier: MIT
"""The torqueloop link protocol, Python side (host tool, cocotb tests).

Everything comes from the single definition torqueloop/spec/protocol.toml,
read at import time; :mod:`torqueloop.flow.gen_protocol` writes the C header
and docs/protocol.md from the same data, so the three can never disagree.

Frame: ``COBS(seq:u16 cmd:u8 len:u8 payload crc:u16) 0x00``, CRC-16/CCITT-FALSE
over seq..payload, all little-endian (docs/protocol.md).
"""

from __future__ import annotations

import math
import struct
import tomllib
from dataclasses import dataclass, field
from pathlib import Path
from torqueloop.spec.refs import resolve
from torqueloop.spec.system import SYSTEM

PROTOCOL_TOML = Path(__file__).resolve().with_name("protocol.toml")
_FMT = {"u8": "B", "i8": "b", "u16": "H", "i16": "h", "u32": "I", "i32": "i", "b16": "16s"}


@dataclass(frozen=True)
class Command:
    name: str
    cmd: int
    desc: str
    req: tuple[tuple[str, str], ...]
    rep: tuple[tuple[str, str], ...]
    feeds_link: bool = False    # executed with a new seq, it feeds the link watchdog
    auth: str = "key"                 # "key": needs a MAC (docs/security.md); "open": may come without
    open_when: dict = field(default_factory=dict)   # field -> value with which a "key" command is open
    handler: str = ""           # the firmware function that runs it (firmware/servo/commands.c)
    seq_checked: bool = True    # executed only with a new seq (False: accepted at any seq, which it leaves)
    read_only: bool = False     # changes nothing on the board
    repeatable: bool = False    # a lost reply: send it again with a fresh seq
    untagged: bool = False      # the host sends it without a MAC even in a session

    @property
    def req_fmt(self) -> str:
        return "<" + "".join(_FMT[t] for _, t in self.req)

    @property
    def rep_fmt(self) -> str:
        return "<" + "".join(_FMT[t] for _, t in self.rep)


@dataclass(frozen=True)
class Param:
    name: str
    id: int
    scope: str
    min: int
    max: int
    defaults: tuple[int, ...]   # per axis (one entry for a global parameter)
    desc: str
    tighten: int = 0            # +1 / -1: while an axis is enabled it may only rise / fall (0: free)

    @property
    def default(self) -> int:
        """Axis 0's default (the only one of a global parameter)."""
        return self.defaults[0]


@dataclass(frozen=True)
class Frame:
    seq: int
    cmd: int
    payload: bytes


@dataclass(frozen=True)
class FrameError:
    """A delimited chunk that is not a valid frame; status names why."""
    status: int
    raw: bytes


def _load() -> dict:
    with open(PROTOCOL_TOML, "rb") as f:
        return tomllib.load(f)


SPEC = _load()
META: dict = SPEC["meta"]
PROTO_VERSION: int = META["version"]
CONFIG_SINCE: int = META["config_since"]   # the oldest protocol whose saved configuration files load
MAX_PAYLOAD: int = META["max_payload"]
HEADER_BYTES: int = META["header_bytes"]
CRC_BYTES: int = META["crc_bytes"]
REPLY_FLAG: int = META["reply_flag"]
TELEMETRY_CMD: int = META["telemetry_cmd"]
ERROR_CMD: int = META["error_cmd"]
SEQ_WINDOW: int = META["seq_window"]
BOOTLOADER_MAGIC: int = META["bootloader_magic"]
#: the parameter store on the board's configuration flash and the EPCS facts it relies on ([store])
STORE: dict[str, int] = SPEC["store"]
FIRMWARE_VERSION: int = META["firmware_version"]
MAX_PACKET = HEADER_BYTES + MAX_PAYLOAD + CRC_BYTES
# COBS adds one byte per 254 plus the leading code byte.
MAX_ENCODED = MAX_PACKET + MAX_PACKET // 254 + 1

STATUS: dict[str, int] = {s["name"]: s["code"] for s in SPEC["status"]}
STATUS_NAME: dict[int, str] = {v: k for k, v in STATUS.items()}
#: the rule that refused a command: the second byte of its error reply ('why')
REFUSAL: dict[str, int] = {r["name"]: r["code"] for r in SPEC["refusal"]}
REFUSAL_NAME: dict[int, str] = {v: k for k, v in REFUSAL.items()}
REFUSAL_DESC: dict[int, str] = {r["code"]: r["desc"] for r in SPEC["refusal"]}
#: the status each rule comes with (NONE: any)
REFUSAL_STATUS: dict[str, int] = {r["name"]: STATUS[r["status"]] for r in SPEC["refusal"] if "status" in r}
FAULT: dict[str, int] = {f["name"]: 1 << f["bit"] for f in SPEC["fault"]}
#: faults that only block motion toward one end (the axis may be enabled and driven back out)
DIRECTIONAL_FAULTS: int = sum(1 << f["bit"] for f in SPEC["fault"] if f.get("blocks") == "direction")


_COMMAND_KEYS = frozenset({"name", "cmd", "desc", "req", "rep", "feeds_link", "auth", "open_when", "handler",
                           "seq", "read_only", "repeatable", "untagged"})


def _command(c: dict) -> Command:
    """One command's descriptor row; repeatable and untagged default to read_only."""
    where = f"protocol.toml command {c.get('name', '?')}"
    unknown = set(c) - _COMMAND_KEYS
    if unknown:
        raise ProtocolSpecError(f"{where}: unknown keys {sorted(unknown)}")
    if c.get("seq", "checked") not in ("checked", "any"):
        raise ProtocolSpecError(f"{where}: seq must be 'checked' or 'any'")
    read_only = bool(c.get("read_only", False))
    cmd = Command(c["name"], c["cmd"], c["desc"], tuple(tuple(x) for x in c["req"]),
                  tuple(tuple(x) for x in c["rep"]), bool(c.get("feeds_link", False)), c.get("auth", ""),
                  dict(c.get("open_when", {})), c.get("handler", ""), c.get("seq", "checked") == "checked",
                  read_only, bool(c.get("repeatable", read_only)), bool(c.get("untagged", read_only)))
    if cmd.auth not in ("key", "open"):
        raise ProtocolSpecError(f"{where}: auth must be 'key' or 'open'")
    if not cmd.handler.startswith("cmd_") or not cmd.handler.isidentifier():
        raise ProtocolSpecError(f"{where}: handler must name a C function cmd_*")
    if cmd.untagged and cmd.auth == "key":
        raise ProtocolSpecError(f"{where}: a command that needs the key cannot be untagged")
    if cmd.read_only and cmd.feeds_link:
        raise ProtocolSpecError(f"{where}: a read-only command does not show the host in control (feeds_link)")
    fields = dict(cmd.req)
    if cmd.open_when and (cmd.auth != "key" or any(fields.get(f) != "u8" for f in cmd.open_when)):
        raise ProtocolSpecError(f"protocol.toml command {cmd.name}: open_when names u8 request fields of a 'key' command")
    return cmd


class ProtocolSpecError(ValueError):
    """protocol.toml breaks a rule; the message names the parameter."""


COMMANDS: dict[str, Command] = {c["name"]: _command(c) for c in SPEC["command"]}
if len({c.handler for c in COMMANDS.values()}) != len(COMMANDS):
    raise ProtocolSpecError("protocol.toml: two commands name the same handler")
#: MOVE mode bits
MOVE_TRAPEZOID = 0x01
MOVE_UNHOMED = 0x80
#: HOME modes and STATUS.home states
HOME_MODES = {"neg": 0, "pos": 1, "here": 2}
HOME_STATE = {0: "not homed", 1: "homing", 2: "homed"}
#: STATUS.limits bits: limit switch open now
LIMIT_BITS = {"neg": 0x01, "pos": 0x02}
BY_CMD: dict[int, Command] = {c.cmd: c for c in COMMANDS.values()}
AXIS_COUNT = len(SYSTEM.axes)
GLOBAL_AXIS = 0xFF
#: a raw gain's default follows from its physical default (and TAU_MAX_MNM, COUNTS_PER_REV)
RAW_GAIN_OF = {"KP_Q16": "KP_UNM_RAD", "KD_Q16": "KD_UNMS_RAD", "KI_Q16": "KI_UNM_RADS"}


def _params(spec: list[dict]) -> dict[str, Param]:
    """The parameter table, defaults resolved: a number, a "system:" reference
    (one value, or one per axis), or for a raw gain "derived" (computed from
    its physical gain's defaults with :func:`gain_raw_from_phys`)."""
    raw: dict[str, dict] = {p["name"]: p for p in spec}

    def per_axis(p: dict) -> tuple[int, ...]:
        n = AXIS_COUNT if p["scope"] == "axis" else 1
        v = p["default"]
        if v == "derived":
            if p["name"] not in RAW_GAIN_OF:
                raise ProtocolSpecError(f"protocol.toml param {p['name']}: only raw gains may be 'derived'")
            phys, tau, cpr = (per_axis(raw[k]) for k in (RAW_GAIN_OF[p["name"]], "TAU_MAX_MNM", "COUNTS_PER_REV"))
            return tuple(gain_raw_from_phys(g, t, c) for g, t, c in zip(phys, tau, cpr))
        v = resolve(v, f"protocol.toml param {p['name']}.default")
        vals = v if isinstance(v, tuple) else (v,) * n
        if len(vals) != n:
            raise ProtocolSpecError(f"protocol.toml param {p['name']}: {len(vals)} defaults for {n} axes")
        return tuple(int(x) for x in vals)

    def bound(p: dict, k: str) -> int:
        v = resolve(p[k], f"protocol.toml param {p['name']}.{k}")
        if not isinstance(v, int):
            raise ProtocolSpecError(f"protocol.toml param {p['name']}.{k}: one integer, not {v!r}")
        return v

    out = {}
    for p in spec:
        d = per_axis(p)
        lo, hi = bound(p, "min"), bound(p, "max")
        if not all(lo <= x <= hi for x in d):
            raise ProtocolSpecError(f"protocol.toml param {p['name']}: default {d} outside {lo}..{hi}")
        t = p.get("tighten")
        if t not in (None, "up", "down"):
            raise ProtocolSpecError(f"protocol.toml param {p['name']}: tighten must be 'up' or 'down', not {t!r}")
        out[p["name"]] = Param(p["name"], p["id"], p["scope"], lo, hi, d, p["desc"],
                               {"up": 1, "down": -1, None: 0}[t])
    return out


PARAM_BY_ID: dict[int, Param] = {}
TELEMETRY_HEAD: tuple[tuple[str, str], ...] = tuple(tuple(x) for x in SPEC["telemetry"]["head"])
TELEMETRY_AXIS: tuple[tuple[str, str], ...] = tuple(tuple(x) for x in SPEC["telemetry"]["axis"])


# --- framing -------------------------------------------------------------------

def crc16(data: bytes, crc: int = 0xFFFF) -> int:
    """CRC-16/CCITT-FALSE (check value of b'123456789' is 0x29B1)."""
    for b in data:
        crc ^= b << 8
        for _ in range(8):
            crc = ((crc << 1) ^ 0x1021) & 0xFFFF if crc & 0x8000 else (crc << 1) & 0xFFFF
    return crc


def cobs_encode(data: bytes) -> bytes:
    out = bytearray([0])
    code_at, code = 0, 1
    for b in data:
        if b == 0:
            out[code_at] = code
            code_at, code = len(out), 1
            out.append(0)
        else:
            out.append(b)
            code += 1
            if code == 0xFF:
                out[code_at] = code
                code_at, code = len(out), 1
                out.append(0)
    out[code_at] = code
    return bytes(out)


def cobs_decode(data: bytes) -> bytes | None:
    """Inverse of cobs_encode; None if ``data`` is not valid COBS."""
    out = bytearray()
    i, n = 0, len(data)
    while i < n:
        code = data[i]
        if code == 0 or i + code > n:
            return None
        block = data[i + 1:i + code]
        if 0 in block:
            return None
        out += block
        i += code
        if code < 0xFF and i < n:
            out.append(0)
    return bytes(out)


def encode_frame(seq: int, cmd: int, payload: bytes = b"") -> bytes:
    """One frame, ready for the wire: 0x00 on both sides, so text the bridge
    inserted before it (``*HELLO*``) ends as its own bad chunk, not glued to the frame."""
    if len(payload) > MAX_PAYLOAD:
        raise ValueError(f"payload of {len(payload)} bytes > {MAX_PAYLOAD}")
    body = struct.pack("<HBB", seq & 0xFFFF, cmd, len(payload)) + payload
    return b"\x00" + cobs_encode(body + struct.pack("<H", crc16(body))) + b"\x00"


def parse_packet(raw: bytes) -> Frame | FrameError:
    """Check one delimiter-free chunk exactly as the firmware does."""
    if len(raw) > MAX_ENCODED:
        return FrameError(STATUS["OVERSIZE"], raw)
    pkt = cobs_decode(raw)
    if pkt is None or len(pkt) < HEADER_BYTES + CRC_BYTES:
        return FrameError(STATUS["FRAMING"], raw)
    if len(pkt) > MAX_PACKET:
        return FrameError(STATUS["OVERSIZE"], raw)
    body, crc = pkt[:-CRC_BYTES], struct.unpack("<H", pkt[-CRC_BYTES:])[0]
    if crc16(body) != crc:
        return FrameError(STATUS["CRC"], raw)
    seq, cmd, ln = struct.unpack("<HBB", body[:HEADER_BYTES])
    if ln != len(body) - HEADER_BYTES:
        return FrameError(STATUS["LENGTH"], raw)
    return Frame(seq, cmd, bytes(body[HEADER_BYTES:]))


class FrameDecoder:
    """Byte-stream to frames: feed whatever arrives, get frames and errors back.
    Text between frames (the RN-XV's ``*HELLO*``) comes back as a FrameError."""

    def __init__(self) -> None:
        self._buf = bytearray()
        self._overflow = False

    def feed(self, data: bytes) -> list[Frame | FrameError]:
        """Every frame and error completed by ``data``, in order.  A list, not
        a generator: a caller that stops reading early must not see a frame
        twice or have the next one merged into the old buffer."""
        out: list[Frame | FrameError] = []
        for b in data:
            if b == 0:
                if self._overflow:
                    out.append(FrameError(STATUS["OVERSIZE"], bytes(self._buf)))
                elif self._buf:
                    out.append(parse_packet(bytes(self._buf)))
                self._buf.clear()
                self._overflow = False
            elif len(self._buf) < MAX_ENCODED:
                self._buf.append(b)
            else:
                self._overflow = True
        return out


# --- payloads ------------------------------------------------------------------

def request(name: str, seq: int, **fields: int) -> bytes:
    c = COMMANDS[name]
    payload = struct.pack(c.req_fmt, *(fields[n] for n, _ in c.req))
    return encode_frame(seq, c.cmd, payload)


def decode_reply(frame: Frame) -> dict[str, int]:
    """Fields of a reply frame by name; an error reply has 'status', and 'why'
    (REFUSAL) when the command's handler refused it (REFUSAL["NONE"] otherwise)."""
    c = BY_CMD.get(frame.cmd & ~REPLY_FLAG)
    if not frame.payload:
        raise ValueError("reply without status")
    status = frame.payload[0]
    if c is None or status != STATUS["OK"]:
        return {"status": status, "why": frame.payload[1] if len(frame.payload) > 1 else REFUSAL["NONE"]}
    vals = struct.unpack(c.rep_fmt, frame.payload)
    return dict(zip((n for n, _ in c.rep), vals))


def decode_telemetry(frame: Frame) -> dict:
    head_fmt = "<" + "".join(_FMT[t] for _, t in TELEMETRY_HEAD)
    ax_fmt = "<" + "".join(_FMT[t] for _, t in TELEMETRY_AXIS)
    hs, asz = struct.calcsize(head_fmt), struct.calcsize(ax_fmt)
    out: dict = dict(zip((n for n, _ in TELEMETRY_HEAD), struct.unpack(head_fmt, frame.payload[:hs])))
    out["axes"] = [dict(zip((n for n, _ in TELEMETRY_AXIS),
                            struct.unpack(ax_fmt, frame.payload[hs + i * asz:hs + (i + 1) * asz])))
                   for i in range(AXIS_COUNT)]
    return out


def telemetry_payload_bytes() -> int:
    return (struct.calcsize("<" + "".join(_FMT[t] for _, t in TELEMETRY_HEAD))
            + AXIS_COUNT * struct.calcsize("<" + "".join(_FMT[t] for _, t in TELEMETRY_AXIS)))


# --- physical units (the same integer arithmetic as firmware/servo/control.c) ----

TWO_PI_NUM, TWO_PI_DEN = 710, 113   # 2 pi to 2.7e-7, the rational the firmware uses


def gain_raw_from_phys(micro: int, tau_max_mnm: int, counts_per_rev: int) -> int:
    """q16 PWM steps per count (or per count/s, per count*s) from micro N m per rad
    (per rad/s, per rad s): raw = g / tau_max * M / (counts_per_rev / 2 pi) * 2^16, M = 1023."""
    num = micro * SYSTEM.pwm_full * 65536 * TWO_PI_NUM
    den = tau_max_mnm * 1000 * counts_per_rev * TWO_PI_DEN
    return min(0x7FFF_FFFF, (num + den // 2) // den)


def gain_phys_from_raw(raw: int, tau_max_mnm: int, counts_per_rev: int) -> int:
    num = raw * tau_max_mnm * 1000 * counts_per_rev * TWO_PI_DEN
    den = SYSTEM.pwm_full * 65536 * TWO_PI_NUM
    return min(100_000_000, (num + den // 2) // den)


def counts_to_rad(counts: int, counts_per_rev: int = SYSTEM.counts_per_turn) -> float:
    return counts * 2 * math.pi / counts_per_rev


def counts_to_mm(counts: int, counts_per_rev: int = SYSTEM.counts_per_turn,
                 pitch_um: int = SYSTEM.lead_um) -> float:
    return counts * pitch_um / 1000 / counts_per_rev


PARAMS: dict[str, Param] = _params(SPEC["param"])
PARAM_BY_ID.update({p.id: p for p in PARAMS.values()})


def param_layout() -> int:
    """The stored record's layout word ([store]): CRC-32 of the parameters' (id, global)
    in table order, so a firmware with other parameters ignores a record it cannot read."""
    import zlib
    return zlib.crc32(bytes(b for p in PARAMS.values() for b in (p.id, int(p.scope == "global")))) & 0xFFFF_FFFF
