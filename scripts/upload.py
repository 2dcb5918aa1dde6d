#!/usr/bin/env python3
"""Upload a firmware image to the torqueloop boot ROM bootloader (docs/bootloader.md).

    python scripts/upload.py IMAGE --port URL [--baud 115200] [--enter] [--wait S]

IMAGE: a RAM-linked ELF (build/firmware/servo/servo.elf) or its flat .bin.
URL:   a serial port (/dev/ttyUSB0) or the RN-XV's TCP bridge (socket://192.168.1.50:2000).
--enter: ask the running servo firmware to jump to the bootloader first (IDENTIFY for
         its last seq, then BOOTLOADER with the magic); without it, press the board's
         reset while the script waits for the bootloader's window (TLBW).
Exit status 0 when the bootloader accepted and started the image, 1 otherwise.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(REPO))

from torqueloop import bootproto as bp  # noqa: E402


def servo_enter(port, timeout_s: float = 2.0) -> bytes:
    """The BOOTLOADER request for the running servo firmware, with a seq it
    will accept (one past the last seq its IDENTIFY reply reports)."""
    from torqueloop import protocol as P

    port.write(P.request("IDENTIFY", 0))
    dec = P.FrameDecoder()
    end = time.monotonic() + timeout_s
    while time.monotonic() < end:
        for f in dec.feed(port.read(max(1, port.in_waiting or 1))):
            if isinstance(f, P.Frame) and f.cmd == (P.COMMANDS["IDENTIFY"].cmd | 0x80):
                last = P.decode_reply(f).get("last_seq", 0)
                return P.request("BOOTLOADER", (last + 1) & 0xFFFF, magic=P.BOOTLOADER_MAGIC)
    raise TimeoutError("the servo firmware did not answer IDENTIFY (is it running, is the baud rate right?)")


def progress_bar(sent: int, total: int) -> None:
    width = 40
    done = width * sent // total
    sys.stderr.write(f"\r[{'#' * done}{'.' * (width - done)}] {sent}/{total} bytes")
    if sent == total:
        sys.stderr.write("\n")
    sys.stderr.flush()


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("image", type=Path)
    ap.add_argument("--port", required=True, help="serial port or socket://host:2000")
    ap.add_argument("--baud", type=int, default=bp.BAUD, help="UART rate (also paces TCP writes)")
    ap.add_argument("--enter", action="store_true", help="send the servo firmware's BOOTLOADER command first")
    ap.add_argument("--wait", type=float, default=30.0, help="seconds to wait for the window (TLBW)")
    args = ap.parse_args(argv)

    try:
        image = bp.load_image(args.image)
    except (OSError, bp.ImageError) as e:
        print(f"upload: {e}", file=sys.stderr)
        return 1
    print(f"{args.image}: {len(image)} bytes, CRC-32 0x{bp.crc32(image):08x}, "
          f"{len(image) + bp.FRAME_OVERHEAD} bytes on the wire (~{(len(image) + bp.FRAME_OVERHEAD) * 10 / args.baud:.1f} s)")

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
                enter = servo_enter(port)
            except TimeoutError as e:
                print(f"upload: {e}", file=sys.stderr)
                return 1
        else:
            print(f"waiting up to {args.wait:g} s for the bootloader: reset the board now", file=sys.stderr)
        res = bp.upload(args.port, image, baud=args.baud, wait_window_s=args.wait, enter=enter,
                        progress=progress_bar, port=port)
    finally:
        port.close()
    print(("OK: " if res.ok else "FAILED: ") + res.message + f" ({res.seconds:.1f} s)")
    return 0 if res.ok else 1


if __name__ == "__main__":
    sys.exit(main())
