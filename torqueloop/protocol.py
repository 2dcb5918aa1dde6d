"""The torqueloop link protocol, Python side (host tool, cocotb tests).

Everything comes from the single definition firmware/protocol/protocol.toml,
read at import time; scripts/gen_protocol.py writes the C header and
docs/protocol.md from the same data through :func:`c_header` and
:func:`markdown`, so the three can never disagree.

Frame: ``COBS(seq:u16 cmd:u8 len:u8 payload crc:u16) 0x00``, CRC-16/CCITT-FALSE
over seq..payload, all little-endian (docs/protocol.md).
"""

from __future__ import annotations

import math
import struct
import tomllib
from dataclasses import dataclass
from pathlib import Path

PROTOCOL_TOML = Path(__file__).resolve().parent.parent / "firmware" / "protocol" / "protocol.toml"
_FMT = {"u8": "B", "i8": "b", "u16": "H", "i16": "h", "u32": "I", "i32": "i"}


@dataclass(frozen=True)
class Command:
    name: str
    cmd: int
    desc: str
    req: tuple[tuple[str, str], ...]
    rep: tuple[tuple[str, str], ...]

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
    default: int
    desc: str


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
MAX_PAYLOAD: int = META["max_payload"]
HEADER_BYTES: int = META["header_bytes"]
CRC_BYTES: int = META["crc_bytes"]
REPLY_FLAG: int = META["reply_flag"]
TELEMETRY_CMD: int = META["telemetry_cmd"]
ERROR_CMD: int = META["error_cmd"]
SEQ_WINDOW: int = META["seq_window"]
BOOTLOADER_MAGIC: int = META["bootloader_magic"]
FIRMWARE_VERSION: int = META["firmware_version"]
MAX_PACKET = HEADER_BYTES + MAX_PAYLOAD + CRC_BYTES
# COBS adds one byte per 254 plus the leading code byte.
MAX_ENCODED = MAX_PACKET + MAX_PACKET // 254 + 1

STATUS: dict[str, int] = {s["name"]: s["code"] for s in SPEC["status"]}
STATUS_NAME: dict[int, str] = {v: k for k, v in STATUS.items()}
FAULT: dict[str, int] = {f["name"]: 1 << f["bit"] for f in SPEC["fault"]}
COMMANDS: dict[str, Command] = {
    c["name"]: Command(c["name"], c["cmd"], c["desc"],
                       tuple(tuple(x) for x in c["req"]), tuple(tuple(x) for x in c["rep"]))
    for c in SPEC["command"]}
BY_CMD: dict[int, Command] = {c.cmd: c for c in COMMANDS.values()}
PARAMS: dict[str, Param] = {p["name"]: Param(p["name"], p["id"], p["scope"], p["min"], p["max"],
                                             p["default"], p["desc"]) for p in SPEC["param"]}
PARAM_BY_ID: dict[int, Param] = {p.id: p for p in PARAMS.values()}
TELEMETRY_HEAD: tuple[tuple[str, str], ...] = tuple(tuple(x) for x in SPEC["telemetry"]["head"])
TELEMETRY_AXIS: tuple[tuple[str, str], ...] = tuple(tuple(x) for x in SPEC["telemetry"]["axis"])
AXIS_COUNT = 2
GLOBAL_AXIS = 0xFF


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
    """Fields of a reply frame by name; an error reply has only 'status'."""
    c = BY_CMD.get(frame.cmd & ~REPLY_FLAG)
    if not frame.payload:
        raise ValueError("reply without status")
    status = frame.payload[0]
    if c is None or status != STATUS["OK"]:
        return {"status": status}
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
    (per rad/s, per rad s): raw = g / tau_max * 1023 / (counts_per_rev / 2 pi) * 2^16."""
    num = micro * 1023 * 65536 * TWO_PI_NUM
    den = tau_max_mnm * 1000 * counts_per_rev * TWO_PI_DEN
    return min(0x7FFF_FFFF, (num + den // 2) // den)


def gain_phys_from_raw(raw: int, tau_max_mnm: int, counts_per_rev: int) -> int:
    num = raw * tau_max_mnm * 1000 * counts_per_rev * TWO_PI_DEN
    den = 1023 * 65536 * TWO_PI_NUM
    return min(100_000_000, (num + den // 2) // den)


def counts_to_rad(counts: int, counts_per_rev: int = 8400) -> float:
    return counts * 2 * math.pi / counts_per_rev


def counts_to_mm(counts: int, counts_per_rev: int = 8400, pitch_um: int = 4000) -> float:
    return counts * pitch_um / 1000 / counts_per_rev


# --- generated views ------------------------------------------------------------

def _ctype(t: str) -> str:
    return {"u8": "uint8_t", "i8": "int8_t", "u16": "uint16_t", "i16": "int16_t",
            "u32": "uint32_t", "i32": "int32_t"}[t]


def _size(fields: tuple[tuple[str, str], ...]) -> int:
    return struct.calcsize("<" + "".join(_FMT[t] for _, t in fields))


def c_header() -> str:
    L = ["/* Generated from firmware/protocol/protocol.toml by scripts/gen_protocol.py - do not edit. */",
         "#ifndef TL_PROTOCOL_H", "#define TL_PROTOCOL_H", "", "#include <stdint.h>", ""]
    for k in ("version", "max_payload", "header_bytes", "crc_bytes", "reply_flag", "telemetry_cmd",
              "error_cmd", "seq_window", "bootloader_magic", "firmware_version"):
        L.append(f"#define TLP_{k.upper()} 0x{META[k]:X}u")
    L += [f"#define TLP_MAX_PACKET {MAX_PACKET}u", f"#define TLP_MAX_ENCODED {MAX_ENCODED}u",
          f"#define TLP_MAX_WIRE {MAX_ENCODED + 2}u  /* 0x00 COBS 0x00 */", ""]
    for n, v in STATUS.items():
        L.append(f"#define TLP_ST_{n} {v}u")
    L.append("")
    for n, v in FAULT.items():
        L.append(f"#define TLP_FAULT_{n} 0x{v:02X}u")
    L.append("")
    for c in COMMANDS.values():
        L.append(f"#define TLP_CMD_{c.name} 0x{c.cmd:02X}u")
        L.append(f"#define TLP_CMD_{c.name}_REQ_LEN {_size(c.req)}u")
        L.append(f"#define TLP_CMD_{c.name}_REP_LEN {_size(c.rep)}u")
    L.append("")
    L.append("/* Field offsets in the payloads (little-endian). */")
    for c in COMMANDS.values():
        for which, fields in (("REQ", c.req), ("REP", c.rep)):
            off = 0
            for n, t in fields:
                L.append(f"#define TLP_{c.name}_{which}_{n.upper()} {off}u")
                off += struct.calcsize(_FMT[t])
    off = 0
    for n, t in TELEMETRY_HEAD:
        L.append(f"#define TLP_TELEM_{n.upper()} {off}u")
        off += struct.calcsize(_FMT[t])
    L.append(f"#define TLP_TELEM_HEAD_LEN {off}u")
    off = 0
    for n, t in TELEMETRY_AXIS:
        L.append(f"#define TLP_TELEM_AX_{n.upper()} {off}u")
        off += struct.calcsize(_FMT[t])
    L += [f"#define TLP_TELEM_AX_LEN {off}u", f"#define TLP_TELEM_LEN {telemetry_payload_bytes()}u", ""]
    L.append("#define TLP_GLOBAL_AXIS 0xFFu")
    for p in PARAMS.values():
        L.append(f"#define TLP_P_{p.name} {p.id}u")
    L += ["", "typedef struct { uint8_t id; uint8_t global; int32_t min; int32_t max; int32_t dflt; } tlp_param_info_t;",
          f"#define TLP_PARAM_COUNT {len(PARAMS)}u",
          "static const tlp_param_info_t TLP_PARAM_INFO[TLP_PARAM_COUNT] = {"]
    for p in PARAMS.values():
        mn = f"(-{-p.min}L)" if p.min < 0 else f"{p.min}L"
        L.append(f"    {{{p.id}u, {1 if p.scope == 'global' else 0}u, {mn}, {p.max}L, "
                 f"{'(-%dL)' % -p.default if p.default < 0 else '%dL' % p.default}}},  /* {p.name} */")
    L += ["};", "", "#endif", ""]
    return "\n".join(L)


def markdown() -> str:
    L = ["<!-- Generated from firmware/protocol/protocol.toml by scripts/gen_protocol.py - do not edit. -->",
         "# torqueloop link protocol", "",
         "The WiFi link of the paper (section V.A): desired positions and controller gains go down, "
         "position error, positions and velocities come up.  Defined once in "
         "`firmware/protocol/protocol.toml`; this page, `firmware/protocol/tl_protocol.h` and "
         "`torqueloop/protocol.py` come from it.", "",
         "## Framing", "",
         "```", "wire:   0x00  COBS( seq:u16  cmd:u8  len:u8  payload[len]  crc:u16 )  0x00", "```", "",
         "Both sides send a 0x00 before and after every frame: text the RN-XV inserts between frames "
         "(`*HELLO*`) then ends as a chunk of its own instead of corrupting the next frame.", "",
         "* **COBS** removes every zero byte from the packet, so `0x00` only ever ends a frame. "
         "After noise, a lost byte or text injected by the RN-XV TCP bridge (`*HELLO*`, `*OPEN*`, `*CLOS*`), "
         "the receiver is back in step at the next `0x00`; the damaged chunk is counted and answered "
         "with an error, never executed.",
         "* **CRC-16/CCITT-FALSE** (poly 0x1021, init 0xFFFF) over seq..payload, little-endian. "
         "A 16-bit CRC misses a random corruption with probability 2^-16 *and* the length, COBS structure "
         "and per-command payload length must also agree.",
         f"* **len** must equal the payload bytes received; the payload is at most {MAX_PAYLOAD} bytes "
         f"(packet {MAX_PACKET}, encoded at most {MAX_ENCODED} + delimiter). A longer chunk is OVERSIZE.",
         f"* **seq** (u16): a command is executed only if its seq is newer than the last accepted one "
         f"(within {SEQ_WINDOW:#x} ahead, modulo 2^16); the same seq again is a retransmission and is answered "
         "with REPLAY without being executed, so a replayed or duplicated frame never moves a motor twice. "
         "After reset any first seq is accepted. IDENTIFY is accepted at any seq and reports the last "
         "accepted seq, so a reconnecting host continues from there.",
         f"* **Replies** carry the command's seq and cmd | 0x{REPLY_FLAG:02X}; the first payload byte is the status. "
         f"A chunk too damaged to trust its seq is answered with seq 0, cmd 0x{ERROR_CMD:02X} and the status.",
         f"* **Telemetry** frames (cmd 0x{TELEMETRY_CMD:02X}) carry a running count as seq.", "",
         f"Protocol version {PROTO_VERSION}.  Default link 115200 baud 8N1 (parameter BAUD_DIV).", "",
         "## Status codes", "", "| code | name | meaning |", "|---|---|---|"]
    for s in SPEC["status"]:
        L.append(f"| {s['code']} | {s['name']} | {s['desc']} |")
    L += ["", "## Fault flags (per axis, latched)", "", "| bit | name | cause |", "|---|---|---|"]
    for f in SPEC["fault"]:
        L.append(f"| {f['bit']} | {f['name']} | {f['desc']} |")
    L += ["", "## Commands", ""]
    for c in COMMANDS.values():
        L.append(f"### 0x{c.cmd:02X} {c.name}")
        L += ["", c.desc, ""]
        L.append("request: " + (", ".join(f"`{n}:{t}`" for n, t in c.req) or "(empty)"))
        L.append("")
        L.append(f"reply (0x{c.cmd | REPLY_FLAG:02X}): " + ", ".join(f"`{n}:{t}`" for n, t in c.rep))
        L.append("")
    L += ["## Telemetry (0x%02X)" % TELEMETRY_CMD, "",
          "head: " + ", ".join(f"`{n}:{t}`" for n, t in TELEMETRY_HEAD) + "; then for axis 0 and 1: "
          + ", ".join(f"`{n}:{t}`" for n, t in TELEMETRY_AXIS) + f" ({telemetry_payload_bytes()} bytes).",
          "velocity_q8 is counts/s x 256.", "",
          "## Parameters", "", "| id | name | scope | min | max | default | meaning |", "|---|---|---|---|---|---|---|"]
    for p in PARAMS.values():
        L.append(f"| {p.id} | {p.name} | {p.scope} | {p.min} | {p.max} | {p.default} | {p.desc} |")
    L += ["", "Global parameters are addressed with axis 0xFF.", ""]
    return "\n".join(L)
