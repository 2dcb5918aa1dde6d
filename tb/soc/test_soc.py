# SPDX-License-Identifier: MIT
"""soc: the CPU running a real program from the boot ROM on the whole SoC.

tb/soc/prog/blink.c (compiled here with riscv64-unknown-elf-gcc, using only
the generated register header) toggles LEDR[0] from the machine-timer
interrupt (its handler runs from RAM, preloaded through RAM_INIT), copies SW to LEDR[9:1], counts KEY presses from the INTC's
external interrupt onto HEX0 and answers each press with 'K' on the UART.
The bench checks all of it on the pins, with an independent UART model
(cocotbext-uart) on the TX line.  It exercises reset vector, ROM fetch,
.data copy to RAM, stack, the timer compare, INTC -> irq_external, GPIO
synchronisers and edge capture, and the UART page.
"""

from __future__ import annotations

import os
import random
import subprocess
from pathlib import Path

import cocotb
import pytest
from cocotb.clock import Clock
from cocotb.triggers import ClockCycles, FallingEdge, RisingEdge

from torqueloop.spec import regs
from torqueloop.flow.manifest import REPO_ROOT
from torqueloop.flow.simrun import BUILD_ROOT, run, sims_for

PROG = Path(__file__).resolve().parent / "prog"
HALF_PERIOD = 400          # blink.c
RAM_BYTES_TB = 4096        # link.ld
SEG_DIGITS = [0x3F, 0x06, 0x5B, 0x4F, 0x66, 0x6D, 0x7D, 0x07, 0x7F, 0x6F]
UART_BAUD = 115_200        # the UART core's default (BAUD_DIV = 0); 434 clocks per bit


class Cycles:
    def __init__(self, clk) -> None:
        self.n = 0
        cocotb.start_soon(self._run(clk))

    async def _run(self, clk) -> None:
        while True:
            await RisingEdge(clk)
            self.n += 1


async def _toggle_times(dut, cyc: Cycles, count: int, limit: int) -> list[int]:
    times: list[int] = []
    last = int(dut.ledr.value) & 1
    for _ in range(limit):
        await FallingEdge(dut.clk)
        now = int(dut.ledr.value) & 1
        if now != last:
            times.append(cyc.n)
            last = now
            if len(times) == count:
                break
    return times


@cocotb.test()
async def firmware_blinks_counts_keys_and_talks(dut):
    from cocotbext.uart import UartSink

    cocotb.start_soon(Clock(dut.clk, 20, unit="ns").start())
    cyc = Cycles(dut.clk)
    sw = random.getrandbits(9)
    dut.sw.value = sw
    dut.key_n.value = 0xF
    dut.bridge_fault.value = 0
    dut.enc_a.value = 0
    dut.enc_b.value = 0
    dut.enc_z.value = 0
    dut.uart_rx.value = 1
    dut.uart_cts_n.value = 0
    dut.estop.value = 0
    sink = UartSink(dut.uart_tx, baud=UART_BAUD, bits=8)
    dut.rst.value = 1
    await ClockCycles(dut.clk, 5)
    dut.rst.value = 0

    # Timer interrupt: LEDR[0] toggles every HALF_PERIOD cycles on average;
    # each edge is late by at most the main loop's latency.
    times = await _toggle_times(dut, cyc, 6, 20 * HALF_PERIOD)
    assert len(times) == 6, f"LEDR[0] toggled {len(times)} times in {20 * HALF_PERIOD} cycles"
    gaps = [b - a for a, b in zip(times, times[1:])]
    assert all(HALF_PERIOD - 80 <= g <= HALF_PERIOD + 80 for g in gaps), f"toggle intervals {gaps}"
    mean = (times[-1] - times[0]) / (len(times) - 1)
    assert abs(mean - HALF_PERIOD) <= 20, f"mean interval {mean:.1f}, expected {HALF_PERIOD}"
    assert (int(dut.ledr.value) >> 1) == sw, "LEDR[9:1] must follow SW[8:0]"
    assert int(dut.hex0_n.value) == (~SEG_DIGITS[0] & 0x7F), "HEX0 shows 0 before any press"
    assert int(dut.hex5_n.value) == 0x7F and int(dut.hex4_n.value) == 0x7F, "trap handler saw an unexpected trap"

    # External interrupt through the INTC: each press counts once.
    presses = random.randrange(1, 4)
    for i in range(presses):
        key = random.randrange(4)
        dut.key_n.value = 0xF & ~(1 << key)
        await ClockCycles(dut.clk, 60)
        dut.key_n.value = 0xF
        await ClockCycles(dut.clk, 200)
        assert int(dut.hex0_n.value) == (~SEG_DIGITS[i + 1] & 0x7F), f"HEX0 after press {i + 1}"
    sw2 = random.getrandbits(9)
    dut.sw.value = sw2
    got = bytearray()
    for _ in range(presses):
        got += await sink.read(1)
    assert bytes(got) == b"K" * presses, f"UART carried {bytes(got)!r}"
    assert (int(dut.ledr.value) >> 1) == sw2
    # The program is still blinking after all that.
    assert len(await _toggle_times(dut, cyc, 2, 4 * HALF_PERIOD)) == 2


def write_if_changed(path: Path, text: str) -> None:
    """Atomic, and untouched when identical: other engineers' test runs may
    be reading the same image at this moment (a simulator reading a
    half-written hex file would boot garbage)."""
    if path.exists() and path.read_text() == text:
        return
    tmp = path.with_name(f"{path.name}.{os.getpid()}.tmp")
    tmp.write_text(text)
    tmp.replace(path)


def _hex_words(data: bytes, size: int) -> str:
    assert len(data) <= size, f"{len(data)} bytes do not fit {size}"
    data += bytes(size - len(data))
    return "".join(f"{int.from_bytes(data[i:i + 4], 'little'):08x}\n" for i in range(0, size, 4))


def build_images(name: str = "blink") -> tuple[Path, Path]:
    """Compile tb/soc/prog/<name>.c; return the boot-ROM and RAM hex images
    (one word per line): ROM = code, constants and the .data load image;
    RAM = the .ramtext section (code that runs from RAM)."""
    out = BUILD_ROOT / "soc" / "prog"
    out.mkdir(parents=True, exist_ok=True)
    tag = f"{name}.{os.getpid()}"
    elf, rom_bin, ram_bin = out / f"{tag}.elf", out / f"{tag}.rom.bin", out / f"{tag}.ram.bin"
    subprocess.run(
        ["riscv64-unknown-elf-gcc", "-march=rv32im_zicsr", "-mabi=ilp32", "-O2", "-nostdlib",
         "-ffreestanding", "-static", "-std=c11", "-Wall", "-Wextra", "-Werror",
         "-I", str(REPO_ROOT / "firmware" / "include"), "-T", str(PROG / "link.ld"),
         "-Wl,--no-warn-rwx-segments", "-o", str(elf), str(PROG / "crt0.S"), str(PROG / f"{name}.c")],
        check=True, capture_output=True, text=True)
    objcopy = "riscv64-unknown-elf-objcopy"
    subprocess.run([objcopy, "-O", "binary", "-R", ".ramtext", str(elf), str(rom_bin)], check=True)
    subprocess.run([objcopy, "-O", "binary", "-j", ".ramtext", str(elf), str(ram_bin)], check=True)
    rom_text = _hex_words(rom_bin.read_bytes(), regs.BOOT_ROM_SIZE)
    ram_data = ram_bin.read_bytes()
    assert ram_data, "no .ramtext: the handler must run from RAM"
    ram_text = _hex_words(ram_data, RAM_BYTES_TB)
    elf.replace(out / f"{name}.elf")
    rom_bin.unlink()
    ram_bin.unlink()
    rom_hex, ram_hex = out / f"{name}.rom.hex", out / f"{name}.ram.hex"
    write_if_changed(rom_hex, rom_text)
    write_if_changed(ram_hex, ram_text)
    return rom_hex, ram_hex


@pytest.mark.parametrize("sim", sims_for("soc"))
def test_soc(sim):
    rom, ram = build_images()
    run("soc", sim, "test_soc",
        parameters={"RAM_BYTES": RAM_BYTES_TB, "ROM_INIT": f'"{rom}"', "RAM_INIT": f'"{ram}"'})
