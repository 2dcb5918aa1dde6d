# SPDX-License-Identifier: MIT
"""Generated views of the link protocol (torqueloop/spec/protocol.toml): the
firmware's C header and docs/protocol.md.  torqueloop.spec.protocol reads
the TOML itself (no generated Python to go stale)."""

from __future__ import annotations

import struct

from torqueloop.spec import protocol as P


def _ctype(t: str) -> str:
    return {"u8": "uint8_t", "i8": "int8_t", "u16": "uint16_t", "i16": "int16_t",
            "u32": "uint32_t", "i32": "int32_t"}[t]


def _c_int(v: int) -> str:
    return f"(-{-v}L)" if v < 0 else f"{v}L"


def _axis_defaults(p: P.Param) -> tuple[int, ...]:
    """One default per axis (a global parameter's repeated)."""
    return p.defaults if len(p.defaults) == P.AXIS_COUNT else (p.default,) * P.AXIS_COUNT


def _size(fields: tuple[tuple[str, str], ...]) -> int:
    return struct.calcsize("<" + "".join(P._FMT[t] for _, t in fields))


def c_header() -> str:
    L = ["/* Generated from torqueloop/spec/protocol.toml by torqueloop.flow.generate - do not edit. */",
         "#ifndef TL_PROTOCOL_H", "#define TL_PROTOCOL_H", "", "#include <stdint.h>", ""]
    for k in ("version", "max_payload", "header_bytes", "crc_bytes", "reply_flag", "telemetry_cmd",
              "error_cmd", "seq_window", "bootloader_magic", "firmware_version"):
        L.append(f"#define TLP_{k.upper()} 0x{P.META[k]:X}u")
    L += [f"#define TLP_MAX_PACKET {P.MAX_PACKET}u", f"#define TLP_MAX_ENCODED {P.MAX_ENCODED}u",
          f"#define TLP_MAX_WIRE {P.MAX_ENCODED + 2}u  /* 0x00 COBS 0x00 */", ""]
    for n, v in P.STATUS.items():
        L.append(f"#define TLP_ST_{n} {v}u")
    L.append("/* the rule that refused a command: byte TLP_REPLY_WHY of its error reply */")
    L.append("#define TLP_REPLY_WHY 1u")
    for n, v in P.REFUSAL.items():
        L.append(f"#define TLP_WHY_{n} {v}u")
    L += ["/* the status a rule comes with (a constant rule folds to a constant) */",
          "static inline uint8_t tlp_why_status(uint8_t why)", "{", "    switch (why) {"]
    L += [f"    case TLP_WHY_{n}: return TLP_ST_{P.STATUS_NAME[st]};" for n, st in P.REFUSAL_STATUS.items()]
    L += ["    default: return TLP_ST_OK;", "    }", "}", ""]
    for n, v in P.FAULT.items():
        L.append(f"#define TLP_FAULT_{n} 0x{v:04X}u")
    L.append("/* faults that only block motion toward their end: ENABLE is allowed with them latched */")
    L.append(f"#define TLP_FAULT_DIRECTIONAL 0x{P.DIRECTIONAL_FAULTS:04X}u")
    L.append("")
    for c in P.COMMANDS.values():
        L.append(f"#define TLP_CMD_{c.name} 0x{c.cmd:02X}u")
        L.append(f"#define TLP_CMD_{c.name}_REQ_LEN {_size(c.req)}u")
        L.append(f"#define TLP_CMD_{c.name}_REP_LEN {_size(c.rep)}u")
    L += _c_command_table()
    L += [f"#define TLP_MOVE_TRAPEZOID 0x{P.MOVE_TRAPEZOID:02X}u", f"#define TLP_MOVE_UNHOMED 0x{P.MOVE_UNHOMED:02X}u"]
    L += [f"#define TLP_HOME_MODE_{k.upper()} {v}u" for k, v in P.HOME_MODES.items()]
    L += [f"#define TLP_HOME_STATE_{v.upper().replace(' ', '_')} {k}u" for k, v in P.HOME_STATE.items()]
    L += [f"#define TLP_LIMIT_{k.upper()} 0x{v:02X}u" for k, v in P.LIMIT_BITS.items()]
    L.append("")
    L.append("/* Field offsets in the payloads (little-endian). */")
    for c in P.COMMANDS.values():
        for which, fields in (("REQ", c.req), ("REP", c.rep)):
            off = 0
            for n, t in fields:
                L.append(f"#define TLP_{c.name}_{which}_{n.upper()} {off}u")
                off += struct.calcsize(P._FMT[t])
    off = 0
    for n, t in P.TELEMETRY_HEAD:
        L.append(f"#define TLP_TELEM_{n.upper()} {off}u")
        off += struct.calcsize(P._FMT[t])
    L.append(f"#define TLP_TELEM_HEAD_LEN {off}u")
    off = 0
    for n, t in P.TELEMETRY_AXIS:
        L.append(f"#define TLP_TELEM_AX_{n.upper()} {off}u")
        off += struct.calcsize(P._FMT[t])
    L += [f"#define TLP_TELEM_AX_LEN {off}u", f"#define TLP_TELEM_LEN {P.telemetry_payload_bytes()}u", ""]
    L += _c_auth()
    L.append("#define TLP_GLOBAL_AXIS 0xFFu")
    for p in P.PARAMS.values():
        L.append(f"#define TLP_P_{p.name} {p.id}u")
    L += ["", f"#define TLP_AXIS_COUNT {P.AXIS_COUNT}u",
          "/* dflt[axis]: a global parameter's default is dflt[0]; tighten: +1 / -1 = while an axis is",
          "   enabled the value may only rise / fall (a safety limit), 0 = free */",
          "typedef struct { uint8_t id; uint8_t global; int8_t tighten; int32_t min; int32_t max;"
          " int32_t dflt[TLP_AXIS_COUNT]; } tlp_param_info_t;",
          f"#define TLP_PARAM_COUNT {len(P.PARAMS)}u",
          "static const tlp_param_info_t TLP_PARAM_INFO[TLP_PARAM_COUNT] = {"]
    for p in P.PARAMS.values():
        mn = f"(-{-p.min}L)" if p.min < 0 else f"{p.min}L"
        L.append(f"    {{{p.id}u, {1 if p.scope == 'global' else 0}u, {p.tighten}, {mn}, {p.max}L, "
                 f"{{{', '.join(_c_int(d) for d in _axis_defaults(p))}}}}},  /* {p.name} */")
    L.append("};")
    # id -> index: a constant table, so a read with a constant id folds to one load
    index = [-1] * 256
    for k, p in enumerate(P.PARAMS.values()):
        index[p.id] = k
    L += ["/* parameter id -> index into TLP_PARAM_INFO, -1: no such parameter */",
          "static const int8_t TLP_PARAM_INDEX[256] = {"]
    for row in range(0, 256, 16):
        L.append("    " + ", ".join(f"{v:2d}" for v in index[row:row + 16]) + ",")
    L += ["};", "", "#endif", ""]
    return "\n".join(L)


#: descriptor flags of the C command table, in bit order (protocol.toml's command columns)
COMMAND_FLAGS = ("seq_checked", "read_only", "repeatable", "untagged", "feeds_link")


def _c_command_table() -> list[str]:
    """The command descriptors as an X-macro: the firmware expands it into its
    dispatch table (firmware/servo/commands.c) with its own handler type, so
    this header names no servo type."""
    L = ["/* Command descriptor flags (protocol.toml's command columns). */"]
    L += [f"#define TLP_CF_{f.upper()} 0x{1 << k:02X}u" for k, f in enumerate(COMMAND_FLAGS)]
    top = max(c.cmd for c in P.COMMANDS.values())
    L += [f"#define TLP_CMD_LIMIT {top + 1}u   /* command codes are below this */",
          "/* X(code, handler, req_len, rep_len, flags): one row per command; needing the key",
          "   depends on the payload (open_when): tlp_needs_key() */",
          "#define TLP_COMMAND_TABLE(X) \\"]
    rows = []
    for c in P.COMMANDS.values():
        fl = " | ".join(f"TLP_CF_{f.upper()}" for f in COMMAND_FLAGS if getattr(c, f)) or "0u"
        rows.append(f"    X(TLP_CMD_{c.name}, {c.handler}, TLP_CMD_{c.name}_REQ_LEN, TLP_CMD_{c.name}_REP_LEN, {fl})")
    L += [r + " \\" for r in rows[:-1]] + [rows[-1], ""]
    return L


def _c_auth() -> list[str]:
    """The [auth] constants and which command needs the key with which payload."""
    A = P.SPEC["auth"]
    L = ["/* Authentication ([auth] of protocol.toml; docs/security.md). */"]
    for k, v in A.items():
        val = f'"{v}"' if isinstance(v, str) else (f"0x{v:08X}u" if k.endswith("magic") else f"{v}u")
        L.append(f"#define TLP_AUTH_{k.upper()} {val}")
    L.append(f"#define TLP_AUTH_LABEL_BYTES {len(A['label_frame'])}u")
    L += ["/* 1 if cmd with this request payload needs the key (auth = \"key\" and no open_when match). */",
          "static inline int tlp_needs_key(uint8_t cmd, const uint8_t *payload)", "{", "    (void)payload;",
          "    switch (cmd) {"]
    for c in P.COMMANDS.values():
        if c.auth != "key":
            continue
        cond = " || ".join(f"payload[TLP_{c.name}_REQ_{f.upper()}] == {v}u" for f, v in c.open_when.items())
        L.append(f"    case TLP_CMD_{c.name}: return {f'!({cond})' if cond else '1'};")
    L += ["    default: return 0;   /* open, or unknown (answered UNKNOWN_CMD) */", "    }", "}", ""]
    return L


def _auth_text(c: P.Command) -> str:
    if c.auth == "open":
        return "open: no key needed (a MAC may be appended)"
    unless = " or ".join(f"{f} = {v}" for f, v in c.open_when.items())
    return f"needs the key (MAC appended)" + (f", except with {unless}" if unless else "")


def _descriptor_text(c: P.Command) -> str:
    """The command's descriptor row in words (protocol.toml's command columns)."""
    words = [f"handler `{c.handler}`", "sequence-checked" if c.seq_checked else "accepted at any seq"]
    words += [w for w, on in (("read-only", c.read_only), ("repeatable after a lost reply", c.repeatable),
                              ("sent without a MAC", c.untagged)) if on]
    return ", ".join(words)


def markdown() -> str:
    L = ["<!-- Generated from torqueloop/spec/protocol.toml by torqueloop.flow.generate - do not edit. -->",
         "# torqueloop link protocol", "",
         "The WiFi link of the paper (section V.A): desired positions and controller gains go down, "
         "position error, positions and velocities come up.  Defined once in "
         "`torqueloop/spec/protocol.toml`; this page, `firmware/protocol/tl_protocol.h` and "
         "`torqueloop/spec/protocol.py` come from it.", "",
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
         f"* **len** must equal the payload bytes received; the payload is at most {P.MAX_PAYLOAD} bytes "
         f"(packet {P.MAX_PACKET}, encoded at most {P.MAX_ENCODED} + delimiter). A longer chunk is OVERSIZE.",
         f"* **seq** (u16): a command is executed only if its seq is newer than the last accepted one "
         f"(within {P.SEQ_WINDOW:#x} ahead, modulo 2^16); the same seq again is a retransmission and is answered "
         "with REPLAY without being executed, so a replayed or duplicated frame never moves a motor twice. "
         "After reset any first seq is accepted. IDENTIFY is accepted at any seq and reports the last "
         "accepted seq, so a reconnecting host continues from there.",
         f"* **Replies** carry the command's seq and cmd | 0x{P.REPLY_FLAG:02X}; the first payload byte is the status. "
         f"A chunk too damaged to trust its seq is answered with seq 0, cmd 0x{P.ERROR_CMD:02X} and the status.",
         f"* **Telemetry** frames (cmd 0x{P.TELEMETRY_CMD:02X}) carry a running count as seq.",
         f"* **Authentication** ([docs/security.md](security.md)): a command marked \"needs the key\" must end its "
         f"payload with a {P.SPEC['auth']['tag_bytes']}-byte MAC, HMAC-SHA-256 under the board's key over the "
         "session's two nonces (SESSION), seq, cmd, len and the payload, truncated; len counts the MAC. "
         "Open commands (reading, STOP, disabling) work without it. An authenticated command must also be "
         "newer than the session's last authenticated one, whatever other frames did to the seq.", "",
         f"Protocol version {P.PROTO_VERSION}.  Default link 115200 baud 8N1 (parameter BAUD_DIV).", "",
         "## Status codes", "", "| code | name | meaning |", "|---|---|---|"]
    for s in P.SPEC["status"]:
        L.append(f"| {s['code']} | {s['name']} | {s['desc']} |")
    L += ["", "## Refusals", "",
          "A command its handler refuses is answered with two bytes: the status and `why`, the rule that "
          "refused it (the host tool prints it). A frame refused before its command ran (length, key, seq, "
          "MAC) gets the status alone.", "",
          "| why | name | status | rule |", "|---|---|---|---|"]
    for r in P.SPEC["refusal"]:
        L.append(f"| {r['code']} | {r['name']} | {r.get('status', '')} | {r['desc']} |")
    L += ["", "## Fault flags (per axis, u16, latched)", "",
          "Each fault disables the axis when it trips. *blocks*: `enable` - the axis stays disabled until "
          "CLEAR_FAULT (refused while the cause is present); `direction` - the axis may be enabled again, "
          "but motion toward that end is blocked until the fault is cleared. docs/safety.md says what trips "
          "each fault, how fast, and what clears it.", "",
          "| bit | name | blocks | cause |", "|---|---|---|---|"]
    for f in P.SPEC["fault"]:
        L.append(f"| {f['bit']} | {f['name']} | {f.get('blocks', 'enable')} | {f['desc']} |")
    L += ["", "## Commands", ""]
    for c in P.COMMANDS.values():
        L.append(f"### 0x{c.cmd:02X} {c.name}")
        L += ["", c.desc, "", f"authentication: {_auth_text(c)}", "", f"descriptor: {_descriptor_text(c)}", ""]
        L.append("request: " + (", ".join(f"`{n}:{t}`" for n, t in c.req) or "(empty)"))
        L.append("")
        L.append(f"reply (0x{c.cmd | P.REPLY_FLAG:02X}): " + ", ".join(f"`{n}:{t}`" for n, t in c.rep))
        L.append("")
        if c.feeds_link:
            L += ["Feeds the link watchdog (LINK_TIMEOUT_MS) when executed.", ""]
    L += ["## Telemetry (0x%02X)" % P.TELEMETRY_CMD, "",
          "head: " + ", ".join(f"`{n}:{t}`" for n, t in P.TELEMETRY_HEAD) + "; then for axis 0 and 1: "
          + ", ".join(f"`{n}:{t}`" for n, t in P.TELEMETRY_AXIS) + f" ({P.telemetry_payload_bytes()} bytes).",
          "velocity_q8 is counts/s x 256.", "",
          "## Parameters", "",
          "*tighten*: a safety limit that may only be made stricter (lowered, or raised) while any axis is "
          "enabled; a change the other way is refused with LOOSEN.", "",
          "| id | name | scope | min | max | default (x / z where they differ) | tighten | meaning |",
          "|---|---|---|---|---|---|---|---|"]
    for p in P.PARAMS.values():
        dflt = " / ".join(str(d) for d in p.defaults) if len(set(p.defaults)) > 1 else str(p.default)
        t = {1: "up only", -1: "down only", 0: ""}[p.tighten]
        L.append(f"| {p.id} | {p.name} | {p.scope} | {p.min} | {p.max} | {dflt} | {t} | {p.desc} |")
    L += ["", "Global parameters are addressed with axis 0xFF.", ""]
    return "\n".join(L)


OUTPUTS = {
    "firmware/protocol/tl_protocol.h": c_header,
    "docs/protocol.md": markdown,
}
