# SPDX-License-Identifier: MIT
"""Bootloader: ROM budget (code, factory slot, servo image), boot and upload
times at 50 MHz / 115 200 baud by calculation, and the real servo firmware as
the factory image on the simulated SoC (Verilator): time from the window
opening to the factory start and to the servo's first IDENTIFY reply, then
its BOOTLOADER command followed by an upload; and the same SoC with a ROM
that holds no factory image (TLBN, then an upload without a window)."""

from __future__ import annotations

import tempfile
import time
from pathlib import Path

from torqueloop.flow import boot_image as build_boot
from torqueloop.flow import firmware, tb_images
from torqueloop.flow.simrun import run
from torqueloop.spec import bootproto as bp
from torqueloop.spec import regs


def main() -> int:
    board = build_boot.build_boot()
    servo = bp.load_image(firmware.build("servo").elf)
    w = build_boot.symbol_word(board.elf, "boot_window_cycles")
    print(f"boot ROM {regs.BOOT_ROM_SIZE} B: bootloader {board.code_bytes} of {bp.BOOT_CODE_BYTES} B, "
          f"factory slot {bp.FACTORY_MAX_BYTES} B, servo image {len(servo)} B "
          f"({100 * len(servo) / bp.FACTORY_MAX_BYTES:.0f} % of the slot)")
    print(f"window {w} cycles = {w / regs.CLK_HZ * 1e3:.0f} ms; max upload {bp.MAX_IMAGE_BYTES} B")
    for n in (len(servo), bp.MAX_IMAGE_BYTES):
        print(f"  upload of {n} B at {bp.BAUD} baud: {(n + bp.FRAME_OVERHEAD) * 10 / bp.BAUD:.2f} s on the wire")

    # The servo firmware as factory image, at the bench's 1 Mbaud.
    fw = firmware.build("servo_boot_tb", {"TL_DEFAULT_BAUD_DIV": str(tb_images.BOOT_TB_BAUD_DIV)})
    factory = bp.load_image(fw.elf)
    app = tb_images.boot_tb_prog("app")
    rom = build_boot.build_rom(factory, tb_images.BOOT_TB_CFG, name="servo_rom", key=tb_images.TB_KEY)
    with tempfile.TemporaryDirectory() as d:
        out = Path(d) / "times"
        t0 = time.monotonic()
        run("soc", "verilator", "test_bootloader", parameters={"ROM_INIT": f'"{rom}"'}, build_tag="bootloader", bench="bootloader",
            testcase="servo_factory_answers_and_hands_over",
            extra_env={"TB_APP_HEX": app.hex(), "TB_FACTORY_HEX": factory.hex(), "TB_SERVO": str(out)})
        t_f, t_id = map(int, out.read_text().split())
    # Same build, ROM without a factory image: the bootloader must wait for an upload.
    rom.write_text(bp.hex_words(bp.rom_image(build_boot.build_boot(tb_images.BOOT_TB_CFG).bin.read_bytes(), None, tb_images.TB_KEY)))
    try:
        run("soc", "verilator", "test_bootloader", parameters={"ROM_INIT": f'"{rom}"'}, build_tag="bootloader", bench="bootloader",
            testcase="no_factory_waits_for_an_upload",
            extra_env={"TB_APP_HEX": app.hex(), "TB_FACTORY_HEX": factory.hex(), "TB_NO_FACTORY": "1"})
    finally:
        build_boot.build_rom(factory, tb_images.BOOT_TB_CFG, name="servo_rom", key=tb_images.TB_KEY)
    print("ROM without factory image: TLBN, window without timeout, upload loaded and run")
    copy = t_f - tb_images.BOOT_TB_CFG.window_cycles
    print(f"servo as factory (sim, {len(factory)} B): TLBF {t_f} cycles after the window opened "
          f"(window {tb_images.BOOT_TB_CFG.window_cycles} + copy/CRC ~{copy} = {copy / len(factory):.0f} cycles/B "
          f"-> {(w + copy) / regs.CLK_HZ * 1e3:.0f} ms from reset to the servo firmware on the board); "
          f"IDENTIFY answered at {t_id}; BOOTLOADER command + upload OK; sim {time.monotonic() - t0:.0f} s wall")
    return 0
