# SPDX-License-Identifier: MIT
"""The simulated board's boot ROM (docs/bootloader.md state machine) on every
path a host can meet: accepted, header, length, CRC, gap and garbage errors,
silence, and that the firmware answers afterwards with the right build id.
Frames come from torqueloop.spec.bootproto (the protocol's single definition)."""

from __future__ import annotations

import pytest

from torqueloop.spec import protocol as P
from torqueloop.sim.simboard import SimBoard

bp = pytest.importorskip("torqueloop.spec.bootproto")
FACTORY = 0x51B0_0001


@pytest.fixture(scope="module")
def board() -> SimBoard:
    return SimBoard(build_id=FACTORY)


def enter_boot(b: SimBoard) -> None:
    b.restart(FACTORY)
    b.read()
    b.write(P.request("BOOTLOADER", 7, magic=P.BOOTLOADER_MAGIC))
    assert P.decode_reply(next(iter(P.FrameDecoder().feed(b.read()))))["status"] == 0
    b.advance(0.001)
    assert b.read() == b"TLBW\n"


def run(b: SimBoard, seconds: float) -> bytes:
    out = b""
    end = b.t + seconds
    while b.t < end:
        b.advance(0.05)
        out += b.read()
    return out


def build_id(b: SimBoard) -> int:
    b.write(P.request("IDENTIFY", 1))
    return P.decode_reply(next(iter(P.FrameDecoder().feed(b.read()))))["build_id"]


def test_accepted_image_runs_with_its_crc_as_build_id(board: SimBoard) -> None:
    enter_boot(board)
    image = bytes(range(256)) * 10
    board.write(b"*HELLO*" + bp.encode_frame(image))     # chatter before the sync is skipped
    assert run(board, 0.01) == b"TLBK\n"
    assert board.boot is None and build_id(board) == bp.crc32(image)


@pytest.mark.parametrize("frame,code", [
    (bp.encode_header(100, 0, load_addr=0x1234), b"H"),
    (bp.encode_header(0, 0), b"L"),
    (bp.encode_header(bp.MAX_IMAGE_BYTES + 1, 0), b"L"),
    (bp.encode_header(4, 0) + b"abcd", b"C"),
    (bp.encode_header(400, 0) + bytes(100), b"T"),       # the rest never comes
    (b"garbage without a sync", b"G"),
    (b"", b""),                                           # nothing: straight to the factory firmware
])
def test_every_refusal_ends_in_the_factory_firmware(board: SimBoard, frame: bytes, code: bytes) -> None:
    enter_boot(board)
    board.write(frame)
    out = run(board, 1.2)
    assert out == (b"TLB" + code + b"\n" if code else b"") + b"TLBF\n"
    assert board.boot is None and build_id(board) == FACTORY
