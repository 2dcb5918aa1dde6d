#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Upload a firmware image to the torqueloop boot ROM bootloader (docs/bootloader.md).

    python scripts/upload.py IMAGE --port URL [--baud 115200] [--enter] [--wait S]

IMAGE: a RAM-linked ELF (build/firmware/servo/servo.elf) or its flat .bin.
URL:   a serial port (/dev/ttyUSB0) or the RN-XV's TCP bridge (socket://192.168.1.50:2000).
--enter: ask the running servo firmware to jump to the bootloader first (IDENTIFY for
         its last seq, then BOOTLOADER with the magic); without it, press the board's
         reset while the script waits for the bootloader's window (TLBW).
Exit status 0 when the bootloader accepted and started the image, 1 otherwise.
The code is torqueloop.host.upload's (``torqueloop upload`` uses it too).
"""

import sys

from torqueloop.host.upload import main

if __name__ == "__main__":
    sys.exit(main())
