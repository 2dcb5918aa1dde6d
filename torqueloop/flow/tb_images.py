# SPDX-License-Identifier: MIT
"""The images the firmware and bootloader test benches run, defined once:
the benches (tb/firmware, tb/bootloader) and the benchmarks that run their
measurement tests (scripts/benches) both import them from here, so a
benchmark never reads a test module.

* servo_tb: the servo firmware with a 500 us control period and the link
  at 1 Mbaud (50 MHz / (49 + 1) per bit: 500 clocks a byte, so the 16-byte
  RX FIFO outlasts a control iteration), behind a stub ROM holding the
  public test key;
* the bootloader bench: a 40 000-cycle window, a 20 000-cycle gap, 1 Mbaud,
  and RAM-linked test programs from tb/bootloader/prog/.
"""

from __future__ import annotations

import os
import subprocess

from torqueloop.flow import firmware
from torqueloop.flow.boot_image import BootConfig
from torqueloop.flow.manifest import REPO_ROOT
from torqueloop.spec import auth
from torqueloop.spec import bootproto as bp

#: the key every bench's ROM holds (docs/security.md: public, for tests only)
TB_KEY = auth.TEST_KEY

SERVO_TB_BAUD_DIV = 49
SERVO_TB_PERIOD_US = 500
SERVO_TB_DEFINES = {"TL_DEFAULT_PERIOD_US": SERVO_TB_PERIOD_US, "TL_DEFAULT_BAUD_DIV": SERVO_TB_BAUD_DIV}

BOOT_TB_BAUD_DIV = 49
BOOT_TB_CFG = BootConfig(window_cycles=40_000, gap_cycles=20_000, baud_div=BOOT_TB_BAUD_DIV)
BOOT_TB_PROGS = REPO_ROOT / "tb" / "bootloader" / "prog"


def servo_tb_image(key: bytes | None = TB_KEY) -> firmware.Image:
    """The servo firmware as the firmware bench runs it (``key`` None: a ROM without a key)."""
    return firmware.build("servo_tb", {k: str(v) for k, v in SERVO_TB_DEFINES.items()}, key=key)


def boot_tb_prog(name: str) -> bytes:
    """tb/bootloader/prog/<name>.c as a RAM-linked firmware image; the flat
    image comes from bootproto.load_image (the host tool's ELF conversion)."""
    out = REPO_ROOT / "build" / "sim" / "bootloader" / "prog"
    out.mkdir(parents=True, exist_ok=True)
    elf = out / f"{name}.{os.getpid()}.elf"
    fw = REPO_ROOT / "firmware"
    subprocess.run(
        ["riscv64-unknown-elf-gcc", "-march=rv32im_zicsr", "-mabi=ilp32", "-Os", "-nostdlib", "-ffreestanding",
         "-static", "-std=c11", "-Wall", "-Wextra", "-Werror", "-I", str(fw / "include"),
         "-T", str(fw / "common" / "link.ld"), "-Wl,--no-warn-rwx-segments", "-o", str(elf),
         str(fw / "common" / "crt0.S"), str(BOOT_TB_PROGS / f"{name}.c")],
        check=True, capture_output=True, text=True)
    try:
        return bp.load_image(elf)
    finally:
        elf.unlink()
