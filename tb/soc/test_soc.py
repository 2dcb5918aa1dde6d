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

import random
from pathlib import Path

import cocotb
import pytest
from cocotb.triggers import ClockCycles, FallingEdge

from torqueloop.spec import regs
from torqueloop.flow.simrun import BUILD_ROOT, run, sims_for

import tbutil

PROG = Path(__file__).resolve().parent / "prog"
HALF_PERIOD = 400          # blink.c
RAM_BYTES_TB = 4096        # link.ld
SEG_DIGITS = [0x3F, 0x06, 0x5B, 0x4F, 0x66, 0x6D, 0x7D, 0x07, 0x7F, 0x6F]
UART_BAUD = 115_200        # the UART core's default (BAUD_DIV = 0); 434 clocks per bit


async def _toggle_times(dut, count: int, limit: int) -> list[int]:
    times: list[int] = []
    last = int(dut.ledr.value) & 1
    for _ in range(limit):
        await FallingEdge(dut.clk)
        now = int(dut.ledr.value) & 1
        if now != last:
            times.append(tbutil.cycle_now())
            last = now
            if len(times) == count:
                break
    return times


@cocotb.test()
async def firmware_blinks_counts_keys_and_talks(dut):
    tbutil.start_clock(dut)
    sw = random.getrandbits(9)
    tbutil.idle_soc_pins(dut, sw=sw)
    _, sink = tbutil.uart_models(dut.uart_rx, dut.uart_tx, UART_BAUD)
    dut.rst.value = 1
    await ClockCycles(dut.clk, 5)
    dut.rst.value = 0

    # Timer interrupt: LEDR[0] toggles every HALF_PERIOD cycles on average;
    # each edge is late by at most the main loop's latency.
    times = await _toggle_times(dut, 6, 20 * HALF_PERIOD)
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
    assert len(await _toggle_times(dut, 2, 4 * HALF_PERIOD)) == 2


def build_images(name: str = "blink") -> tuple[Path, Path]:
    """Compile tb/soc/prog/<name>.c; return the boot-ROM and RAM hex images
    (one word per line): ROM = code, constants and the .data load image;
    RAM = the .ramtext section (code that runs from RAM)."""
    out = BUILD_ROOT / "soc" / "prog"
    parts = tbutil.soc_prog_sections(PROG / f"{name}.c", out,
                                     {"rom": ["-R", ".ramtext"], "ram": ["-j", ".ramtext"]})
    assert parts["ram"], "no .ramtext: the handler must run from RAM"
    rom_text = tbutil.readmemh(parts["rom"], regs.BOOT_ROM_SIZE)
    ram_text = tbutil.readmemh(parts["ram"], RAM_BYTES_TB)
    rom_hex, ram_hex = out / f"{name}.rom.hex", out / f"{name}.ram.hex"
    tbutil.write_if_changed(rom_hex, rom_text)
    tbutil.write_if_changed(ram_hex, ram_text)
    return rom_hex, ram_hex


@pytest.mark.parametrize("sim", sims_for("soc"))
def test_soc(sim):
    """The SoC as the board builds it (tl_soc's defaults: the pipelined CPU)."""
    _run_soc(sim)


def _run_soc(sim: str, **parameters: object) -> None:
    rom, ram = build_images()
    run("soc", sim, "test_soc",
        parameters={"RAM_BYTES": RAM_BYTES_TB, "ROM_INIT": f'"{rom}"', "RAM_INIT": f'"{ram}"', **parameters})


@pytest.mark.parametrize("sim", [s for s in sims_for("soc") if s == "verilator"])
def test_soc_multi_cycle_cpu(sim):
    """The same program on the SoC with the multi-cycle tl_cpu (CPU_PIPELINED = 0),
    the smaller core a user may still pick: the one SoC-level run that keeps it
    covered (tb/cpu runs both cores on their own)."""
    _run_soc(sim, CPU_PIPELINED=0)
