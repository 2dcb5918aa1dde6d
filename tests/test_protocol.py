# SPDX-License-Identifier: MIT
"""The Python side of the link protocol (torqueloop/spec/protocol.py) against the
protocol's own rules: CRC check value, COBS properties, frame round trips,
resynchronisation after noise and the RN-XV's *HELLO*, every single-bit error
rejected, and the definition's internal consistency."""

from __future__ import annotations

import random
import struct

from torqueloop.spec import protocol as P


def test_crc_check_value() -> None:
    assert P.crc16(b"123456789") == 0x29B1   # CRC-16/CCITT-FALSE catalogue value


def test_cobs_round_trip_and_no_zeros() -> None:
    rng = random.Random(1)
    for n in list(range(0, 600, 7)) + [253, 254, 255, 256, 508]:
        data = bytes(rng.choice([0, rng.randrange(256)]) for _ in range(n))
        enc = P.cobs_encode(data)
        assert 0 not in enc and len(enc) <= n + n // 254 + 1
        assert P.cobs_decode(enc) == data
    assert P.cobs_decode(b"\x05\x01") is None       # block runs past the end


def test_frames_round_trip_and_survive_noise() -> None:
    rng = random.Random(2)
    dec = P.FrameDecoder()
    frames = []
    stream = bytearray(b"*HELLO*")
    for _ in range(200):
        f = P.Frame(rng.randrange(65536), rng.randrange(256), bytes(rng.randrange(256) for _ in range(rng.randrange(65))))
        frames.append(f)
        stream += P.encode_frame(f.seq, f.cmd, f.payload)
        if rng.random() < 0.3:
            stream += bytes(rng.randrange(1, 256) for _ in range(rng.randrange(1, 30))) + b"\x00"
    got = [x for x in dec.feed(bytes(stream)) if isinstance(x, P.Frame)]
    assert got == frames


def test_every_single_bit_error_is_rejected() -> None:
    frame = P.request("MOVE", 77, axis=0, mode=1, target=-12345)
    for bit in range((len(frame) - 1) * 8):
        bad = bytearray(frame)
        bad[bit // 8] ^= 1 << (bit % 8)
        out = list(P.FrameDecoder().feed(bytes(bad)))
        assert not any(isinstance(x, P.Frame) for x in out), f"bit {bit} flip accepted"


def test_oversize_and_length_errors() -> None:
    out = list(P.FrameDecoder().feed(bytes([1 + i % 255 for i in range(300)]) + b"\x00"))
    assert out == [P.FrameError(P.STATUS["OVERSIZE"], out[0].raw)]
    body = struct.pack("<HBB", 1, 7, 5) + b"\x01"          # len says 5, one byte present
    pkt = body + struct.pack("<H", P.crc16(body))
    assert P.parse_packet(P.cobs_encode(pkt)).status == P.STATUS["LENGTH"]
    assert P.parse_packet(P.cobs_encode(b"\x01\x02")).status == P.STATUS["FRAMING"]


def test_definition_is_consistent() -> None:
    assert len({c.cmd for c in P.COMMANDS.values()}) == len(P.COMMANDS)
    assert len({p.id for p in P.PARAMS.values()}) == len(P.PARAMS)
    assert len(set(P.STATUS.values())) == len(P.STATUS)
    for c in P.COMMANDS.values():
        assert c.rep[0] == ("status", "u8"), c.name
        assert struct.calcsize(c.req_fmt) <= P.MAX_PAYLOAD and struct.calcsize(c.rep_fmt) <= P.MAX_PAYLOAD
        assert c.cmd | P.REPLY_FLAG not in (P.TELEMETRY_CMD, P.ERROR_CMD)
    assert P.telemetry_payload_bytes() <= P.MAX_PAYLOAD
    for p in P.PARAMS.values():
        assert p.min <= p.default <= p.max, p.name
    assert P.MAX_ENCODED + 1 <= 80   # a frame fits the firmware's buffers at 115200 baud in < 7 ms


def test_replies_decode_by_name() -> None:
    c = P.COMMANDS["GET_PARAM"]
    f = P.Frame(5, c.cmd | P.REPLY_FLAG, struct.pack(c.rep_fmt, 0, -42))
    assert P.decode_reply(f) == {"status": 0, "value": -42}
    assert P.decode_reply(P.Frame(5, c.cmd | P.REPLY_FLAG, b"\x07")) == {"status": P.STATUS["RANGE"],
                                                                       "why": P.REFUSAL["NONE"]}
    assert P.decode_reply(P.Frame(5, c.cmd | P.REPLY_FLAG, bytes([P.STATUS["RANGE"], P.REFUSAL["PW_ORDER"]]))) == \
        {"status": P.STATUS["RANGE"], "why": P.REFUSAL["PW_ORDER"]}


def test_decoder_stopping_early_never_repeats_or_merges_frames():
    """A reader that takes the first frame and stops must get the second,
    intact, from the next feed, not the first one again."""
    a = P.request("IDENTIFY", 1)
    b = P.request("IDENTIFY", 2)
    dec = P.FrameDecoder()
    first = next(iter(dec.feed(a + b)))
    assert isinstance(first, P.Frame) and first.seq == 1
    rest = [f for f in dec.feed(b"") if isinstance(f, P.Frame)]
    again = [f for f in dec.feed(a) if isinstance(f, P.Frame)]
    assert rest == [] and [f.seq for f in again] == [1]
