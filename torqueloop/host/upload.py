# SPDX-License-Identifier: MIT
"""``torqueloop upload``: the servo firmware's BOOTLOADER command, then the
boot ROM's upload protocol (docs/bootloader.md), then a check that the new
firmware answers.

Images, frames and CRC-32 are ``torqueloop.spec.bootproto``'s, the single
definition of the upload protocol; this module sends them (:func:`upload`)
and chains the steps over the one open link (the RN-XV takes one TCP client, so
the upload must use the connection the BOOTLOADER command went over):

1. IDENTIFY: the running firmware's build id;
2. BOOTLOADER (magic from the protocol definition, authenticated: it needs
   the key): drives off, the firmware jumps to the boot ROM, which answers
   ``TLBW`` and listens;
3. the upload frame, signed with the key (docs/security.md), paced to the
   baud rate, with progress;
4. ``TLBK`` -> the image runs; anything else (``TLBA``: the MAC does not
   verify) -> the bootloader names the error and starts the factory firmware;
5. reconnect (seq starts again) and IDENTIFY: which firmware answers now.
"""

from __future__ import annotations

import argparse
import struct
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable

from torqueloop.spec import auth
from torqueloop.spec import bootproto as bp
from torqueloop.spec import protocol as P

from .client import Client, KeyMissing, ProtocolError


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


class ImageRefused(ValueError):
    """The file is not a firmware image for this board; nothing was sent."""


def load_image(path: str | Path, raw_ok: bool = False) -> bytes:
    """The image to upload, or ImageRefused with one line saying why not
    (bootproto.load_image: an RV32 ELF inside program RAM, or with ``raw_ok``
    a binary carrying the firmware image header)."""
    try:
        image = bp.load_image(path, raw_ok=raw_ok)
        bp.encode_frame(image, bytes(auth.KEY_BYTES))    # size limits, before anything is sent
    except (bp.ImageError, bp.FrameError) as e:
        raise ImageRefused(f"{path}: refused: {e}") from None
    except OSError as e:
        raise ImageRefused(f"{path}: cannot read ({e.strerror or e})") from None
    except struct.error as e:   # a header field that points past the end of a damaged ELF
        raise ImageRefused(f"{path}: refused: damaged ELF ({e})") from None
    return image


def run_upload(client: Client, image: bytes, progress: Callable[[int, int], None] | None = None,
               window_s: float = 5.0, port: Any = None) -> UploadReport:
    """Steps 1-5 above over ``client``'s link (``port`` overrides the link
    the frame goes over, e.g. a test's corrupting wrapper)."""
    t0 = time.monotonic()
    if client.key is None:
        raise KeyMissing("an upload is signed with the link key and BOOTLOADER needs it: name the key file "
                         f"with --key-file FILE or ${auth.KEY_FILE_ENV} (docs/security.md)"
                         + (f" ({client.key_error})" if client.key_error else ""))
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
    res = upload("", image, key=client.key, wait_window_s=0, progress=progress, port=port or client.transport)
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


# --- sending ----------------------------------------------------------------------

@dataclass
class UploadResult:
    ok: bool
    message: str
    replies: list[bp.Reply] = field(default_factory=list)
    bytes_sent: int = 0
    seconds: float = 0.0

    @property
    def factory_running(self) -> bool:
        return bp.Reply.FACTORY in self.replies


Progress = Callable[[int, int], None]


def upload(url: str, image: bytes, *, key: bytes, baud: int = bp.BAUD, wait_window_s: float = 30.0,
           enter: bytes = b"", reply_timeout_s: float = 3.0, chunk: int = 256,
           progress: Progress | None = None, port=None) -> UploadResult:
    """Send ``image``, signed with ``key``, to the bootloader at ``url`` and report what it said.

    ``enter`` is sent first (e.g. the servo firmware's BOOTLOADER command);
    then the window-open reply ``TLBW`` is awaited for ``wait_window_s``
    (0 = send at once), the frame is written in chunks paced to ``baud``
    (a TCP bridge would otherwise buffer faster than its UART drains), and
    replies are read until the bootloader accepts or rejects it.  ``port``
    may be an already open pyserial object (tests); otherwise the URL is opened.
    """
    frame = bp.encode_frame(image, key)
    owned = port is None
    try:
        if port is None:
            import serial  # pyserial; imported here so the frame code works without it

            port = serial.serial_for_url(url, baudrate=baud, timeout=0.05)
        return _send(port, frame, image, baud, wait_window_s, enter, reply_timeout_s, chunk, progress)
    except (OSError, ValueError) as e:   # pyserial's SerialException is an OSError
        return UploadResult(False, f"link lost: {e}")
    finally:
        if owned and port is not None:
            port.close()


def _send(port, frame: bytes, image: bytes, baud: int, wait_window_s: float, enter: bytes,
          reply_timeout_s: float, chunk: int, progress: Progress | None) -> UploadResult:
    parser = bp.ReplyParser()
    replies: list[bp.Reply] = []
    t_start = time.monotonic()

    def read_until(pred: Callable[[bp.Reply], bool], timeout: float) -> bp.Reply | None:
        end = time.monotonic() + timeout
        while time.monotonic() < end:
            for r in parser.feed(port.read(max(1, port.in_waiting or 1))):
                replies.append(r)
                if pred(r):
                    return r
        return None

    if enter:
        port.write(enter)
        port.flush()
    if wait_window_s > 0 and read_until(lambda r: r is bp.Reply.WINDOW, wait_window_s) is None:
        return UploadResult(False, f"no bootloader window (TLBW) within {wait_window_s:g} s: reset the board "
                                   "or send the firmware's BOOTLOADER command", replies, 0,
                            time.monotonic() - t_start)
    sent = 0
    t0 = time.monotonic()
    bytes_per_s = baud / 10.0                 # 8N1: ten bit times per byte
    while sent < len(frame):
        part = frame[sent:sent + chunk]
        port.write(part)
        sent += len(part)
        if progress:
            progress(sent, len(frame))
        ahead = t0 + sent / bytes_per_s - time.monotonic()
        if ahead > 0:
            time.sleep(ahead)
        early = parser.feed(port.read(port.in_waiting)) if port.in_waiting else []
        replies += early
        if any(r.is_error for r in early):
            break
    port.flush()
    terminal = next((r for r in replies if r is bp.Reply.OK or r.is_error), None)
    if terminal is None:
        terminal = read_until(lambda r: r is bp.Reply.OK or r.is_error, reply_timeout_s)
    if terminal is None:
        return UploadResult(False, f"no reply within {reply_timeout_s:g} s after {sent} bytes", replies,
                            sent, time.monotonic() - t_start)
    if terminal is bp.Reply.OK:
        return UploadResult(True, f"{len(image)} bytes, CRC-32 0x{bp.crc32(image):08x}: {bp.REPLY_TEXT[bp.Reply.OK]}",
                            replies, sent, time.monotonic() - t_start)
    read_until(lambda r: r in (bp.Reply.FACTORY, bp.Reply.NO_FACTORY), 2.0 * bp.GAP_MS / 1000 + reply_timeout_s)
    tail = " - factory firmware started" if bp.Reply.FACTORY in replies else ""
    return UploadResult(False, f"rejected: {bp.REPLY_TEXT[terminal]}{tail}", replies, sent,
                        time.monotonic() - t_start)


# --- the standalone uploader (scripts/upload.py): no running firmware needed ------

def servo_enter(port, key: bytes, timeout_s: float = 2.0) -> bytes:
    """The BOOTLOADER request for the running servo firmware: IDENTIFY for a
    seq it will accept (one past the last one it reports), SESSION for a
    challenge, then the request with its MAC (BOOTLOADER needs the key)."""
    dec = P.FrameDecoder()

    def ask(name: str, wire: bytes) -> dict:
        port.write(wire)
        end = time.monotonic() + timeout_s
        while time.monotonic() < end:
            for f in dec.feed(port.read(max(1, port.in_waiting or 1))):
                if isinstance(f, P.Frame) and f.cmd == (P.COMMANDS[name].cmd | P.REPLY_FLAG):
                    return P.decode_reply(f)
        raise TimeoutError(f"the servo firmware did not answer {name} (is it running, is the baud rate right?)")

    last = ask("IDENTIFY", P.request("IDENTIFY", 0)).get("last_seq", 0)
    hn = auth.new_host_nonce()
    rep = ask("SESSION", P.request("SESSION", 0, host_nonce=hn))
    if rep["status"] == P.STATUS["NO_KEY"]:
        raise auth.AuthError("the board has no link key: it refuses BOOTLOADER and every upload (docs/security.md)")
    if rep["status"] != P.STATUS["OK"]:
        raise auth.AuthError(f"SESSION refused: {P.STATUS_NAME.get(rep['status'], rep['status'])}")
    return auth.open_session(key, hn, rep).request("BOOTLOADER", (last + 1) & 0xFFFF, magic=P.BOOTLOADER_MAGIC)


def progress_bar(sent: int, total: int) -> None:
    width = 40
    done = width * sent // total
    sys.stderr.write(f"\r[{'#' * done}{'.' * (width - done)}] {sent}/{total} bytes")
    if sent == total:
        sys.stderr.write("\n")
    sys.stderr.flush()


def main(argv: list[str] | None = None) -> int:
    """scripts/upload.py: upload to the bootloader window after a reset (or
    after the servo's BOOTLOADER command with --enter)."""
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("image", type=Path)
    ap.add_argument("--port", required=True, help="serial port or socket://host:2000")
    ap.add_argument("--baud", type=int, default=bp.BAUD, help="UART rate (also paces TCP writes)")
    ap.add_argument("--enter", action="store_true", help="send the servo firmware's BOOTLOADER command first")
    ap.add_argument("--wait", type=float, default=30.0, help="seconds to wait for the window (TLBW)")
    ap.add_argument("--raw", action="store_true", help="the file is a flat binary with the firmware image header")
    ap.add_argument("-k", "--key-file", help=f"the link key (docs/security.md) [${auth.KEY_FILE_ENV}]")
    args = ap.parse_args(argv)

    try:
        image = load_image(args.image, raw_ok=args.raw)
    except ImageRefused as e:
        print(f"upload: {e}", file=sys.stderr)
        return 2

    path = auth.key_file_path(args.key_file)
    if path is None:
        print(f"upload: an upload is signed with the link key: name its file with --key-file or "
              f"${auth.KEY_FILE_ENV} (docs/security.md)", file=sys.stderr)
        return 1
    try:
        key = auth.read_key_file(path)
    except auth.KeyFileError as e:
        print(f"upload: {e}", file=sys.stderr)
        return 1
    print(f"{args.image}: {len(image)} bytes, CRC-32 0x{bp.crc32(image):08x}, "
          f"{bp.frame_bytes(len(image))} bytes on the wire (~{bp.frame_bytes(len(image)) * 10 / args.baud:.1f} s)")

    import serial

    try:
        port = serial.serial_for_url(args.port, baudrate=args.baud, timeout=0.05)
    except (OSError, ValueError) as e:
        print(f"upload: cannot open {args.port}: {e}", file=sys.stderr)
        return 1
    try:
        enter = b""
        if args.enter:
            try:
                enter = servo_enter(port, key)
            except (TimeoutError, auth.AuthError) as e:
                print(f"upload: {e}", file=sys.stderr)
                return 1
        else:
            print(f"waiting up to {args.wait:g} s for the bootloader: reset the board now", file=sys.stderr)
        res = upload(args.port, image, key=key, baud=args.baud, wait_window_s=args.wait, enter=enter,
                        progress=progress_bar, port=port)
    finally:
        port.close()
    print(("OK: " if res.ok else "FAILED: ") + res.message + f" ({res.seconds:.1f} s)")
    return 0 if res.ok else 1
