"""``torqueloop upload``: the servo firmware's BOOTLOADER command, then the
boot ROM's upload protocol (docs/bootloader.md), then a check that the new
firmware answers.

Images, frames, CRC-32 and the sending loop are ``torqueloop.bootproto``'s,
the single definition of the upload protocol (issue 4); this module only
chains the steps over the one open link (the RN-XV takes one TCP client, so
the upload must use the connection the BOOTLOADER command went over):

1. IDENTIFY: the running firmware's build id;
2. BOOTLOADER (magic from the protocol definition): drives off, the firmware
   jumps to the boot ROM, which answers ``TLBW`` and listens;
3. the upload frame, paced to the baud rate, with progress;
4. ``TLBK`` -> the image runs; anything else -> the bootloader names the
   error and starts the factory firmware;
5. reconnect (seq starts again) and IDENTIFY: which firmware answers now.
"""

from __future__ import annotations

import struct
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable

from .client import Client, ProtocolError


def bootproto() -> Any | None:
    """The upload protocol module, or None while it is not in the tree."""
    try:
        from torqueloop import bootproto as bp
    except ImportError:
        return None
    return bp


NOT_AVAILABLE = ("upload is not available: torqueloop/bootproto.py (the boot ROM upload protocol, "
                 "issue 4) is not in this tree; nothing was sent to the board")


@dataclass(frozen=True)
class UploadReport:
    ok: bool
    message: str
    bytes: int
    crc32: int
    old_build_id: int
    new_build_id: int | None
    replies: list[str]
    seconds: float


def load_image(path: str | Path) -> bytes:
    bp = bootproto()
    if bp is None:
        raise ProtocolError(NOT_AVAILABLE)
    try:
        image = bp.load_image(path)
        bp.encode_frame(image)           # size limits, before anything is sent
    except (bp.ImageError, bp.FrameError, OSError) as e:
        raise ProtocolError(f"{path}: {e}") from None
    except struct.error as e:   # bootproto.image_from_elf reads a truncated ELF header unchecked
        raise ProtocolError(f"{path}: damaged ELF ({e})") from None
    return image


def run_upload(client: Client, image: bytes, progress: Callable[[int, int], None] | None = None,
               window_s: float = 5.0, port: Any = None) -> UploadReport:
    """Steps 1-5 above over ``client``'s link (``port`` overrides the link
    the frame goes over, e.g. a test's corrupting wrapper)."""
    bp = bootproto()
    if bp is None:
        raise ProtocolError(NOT_AVAILABLE)
    t0 = time.monotonic()
    old = client.connect()["build_id"]
    # Wait for the window here, reading through the client: TLBW may come in
    # the same read as the BOOTLOADER reply, or split across reads.
    client.raw_tap = bytearray()
    try:
        client.bootloader()
        end = time.monotonic() + window_s
        while bp.Reply.WINDOW not in bp.ReplyParser().feed(bytes(client.raw_tap)) and time.monotonic() < end:
            client.pump(0.02)
    finally:
        seen, client.raw_tap = bytes(client.raw_tap), None
    early = bp.ReplyParser().feed(seen)
    if bp.Reply.WINDOW not in early:
        raise ProtocolError(f"the board acknowledged BOOTLOADER but no boot ROM window (TLBW) came within "
                            f"{window_s:g} s: the bootloader is not in this FPGA image")
    res = bp.upload("", image, wait_window_s=0, progress=progress, port=port or client.link)
    res.replies[:0] = early
    replies = [r.value for r in res.replies]
    # Whatever runs now (the upload or the factory firmware) starts its seq afresh.
    client.pump(0.05)
    new = None
    deadline = time.monotonic() + 5.0
    while new is None:
        try:
            new = client.connect()["build_id"]
        except ProtocolError:
            if time.monotonic() > deadline:
                raise ProtocolError(f"after the upload ({res.message}) no firmware answers") from None
    return UploadReport(res.ok, res.message, len(image), bp.crc32(image), old, new, replies,
                        time.monotonic() - t0)
