# SPDX-License-Identifier: MIT
"""The simulated board's boot ROM (docs/bootloader.md state machine) on every
path a host can meet: accepted, header, length, CRC, MAC, gap and garbage
errors, silence, a board without a key, and that the firmware answers
afterwards with the right build id.  Frames come from
torqueloop.spec.bootproto (the protocol's single definition)."""

from __future__ import annotations

import pytest

from torqueloop.spec import auth
from torqueloop.spec import protocol as P
from torqueloop.sim.simboard import SimBoard

bp = pytest.importorskip("torqueloop.spec.bootproto")
FACTORY = 0x51B0_0001
KEY = auth.TEST_KEY


@pytest.fixture(scope="module")
def board() -> SimBoard:
    return SimBoard(build_id=FACTORY, key=KEY)


def reply(b: SimBoard) -> dict:
    return P.decode_reply(next(iter(P.FrameDecoder().feed(b.read()))))


def enter_boot(b: SimBoard) -> None:
    b.restart(FACTORY)
    b.read()
    hn = auth.new_host_nonce()
    b.write(P.request("SESSION", 1, host_nonce=hn))
    sess = auth.open_session(KEY, hn, reply(b))
    b.write(sess.request("BOOTLOADER", 7, magic=P.BOOTLOADER_MAGIC))
    assert reply(b)["status"] == 0
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
    board.write(b"*HELLO*" + bp.encode_frame(image, KEY))     # chatter before the sync is skipped
    assert run(board, 0.01) == b"TLBK\n"
    assert board.boot is None and build_id(board) == bp.crc32(image)


@pytest.mark.parametrize("frame,code", [
    (bp.encode_header(100, 0, load_addr=0x1234), b"H"),
    (bp.encode_header(0, 0), b"L"),
    (bp.encode_header(bp.MAX_IMAGE_BYTES + 1, 0), b"L"),
    (bp.encode_header(4, 0) + b"abcd" + bytes(32), b"C"),
    (bp.encode_frame(b"abcd", bytes(32)), b"A"),          # signed with another key
    (bp.encode_frame(b"abcd", KEY)[:-1], b"T"),          # the MAC's last byte never comes
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


def test_a_board_without_a_key_refuses_every_upload() -> None:
    """X after a valid header, then the factory firmware; and BOOTLOADER itself
    is refused by such a board (it needs the key), so only a reset reaches the window."""
    b = SimBoard(build_id=FACTORY, key=None)
    b.write(P.request("BOOTLOADER", 7, magic=P.BOOTLOADER_MAGIC))
    assert reply(b)["status"] == P.STATUS["NO_KEY"] and b.boot is None
    b.reset()                           # the reset button: the boot ROM's window
    b.advance(0.001)
    assert b.read() == b"TLBW\n"
    b.write(bp.encode_frame(bytes(range(64)), KEY))
    assert run(b, 1.2) == b"TLBX\nTLBF\n"
    assert b.boot is None and build_id(b) == FACTORY
