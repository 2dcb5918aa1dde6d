# SPDX-License-Identifier: MIT
"""firmware_store: the parameter store (SAVE, docs/firmware.md "Settings that
survive") on the whole simulated SoC, through the pins.

The servo firmware image of tb/firmware (test_firmware.py's build and its
bench class) runs on tl_soc; the configuration flash is
torqueloop/sim/epcs.py behind the FLASH page's pins (tbutil.EpcsPins: the
EPCS command set, erase to 0xFF, programming ANDs, WIP for the write time,
power cuts).  A reset of the SoC with the flash kept is the power cycle: the
firmware starts afresh and loads what the flash holds.

Checked: a save comes back after the reset; the report says when the running
parameters differ; the second save goes to the other sector; a power loss
during the sector erase, during each page program, and right after the last
page leaves the older copy (or the complete new one, when the last page was
written) - never a mix, never the defaults.

Verilator only, as test_firmware.
"""

from __future__ import annotations

import cocotb
import pytest
from cocotb.triggers import ClockCycles, Timer
from cocotb.utils import get_sim_time

from torqueloop.sim.epcs import SECTOR_BYTES, Epcs
from torqueloop.spec import protocol as P

import tbutil
from test_firmware import KEY, PERIOD_US, TB

#: the model's write times, shortened (the firmware waits by READ STATUS, whatever they are)
PROGRAM_S, ERASE_S = 20e-6, 200e-6
VALUES_A = {(0, "KP_UNM_RAD"): 450_000, (1, "PW0"): 30, (0, "STALL_MS"): 700}
VALUES_B = {(0, "KP_UNM_RAD"): 910_000, (1, "PW0"): 60, (0, "STALL_MS"): 300}


async def boot(tb: TB) -> None:
    """Reset (the flash keeps what it holds), boot, open a session."""
    tb.sess = None
    tb.dut.rst.value = 1
    await ClockCycles(tb.dut.clk, 5)
    tb.dut.rst.value = 0
    # boot: the key's setup and both flash slots read before the UART listens
    await Timer(2 * PERIOD_US + 3000, unit="us")
    await tb.open_session()


async def start(dut) -> tuple[TB, Epcs]:
    tb = TB(dut)
    tb.reply_timeout_us = 20_000          # a SAVE reads, erases, programs and reads back: ~2 ms here
    flash = Epcs(program_s=PROGRAM_S, erase_s=ERASE_S)
    tbutil.EpcsPins(dut, flash)
    await tb.start(session=False)
    await Timer(2000, unit="us")
    await tb.open_session()
    return tb, flash


async def put(tb: TB, values: dict) -> None:
    for (ax, name), v in values.items():
        await tb.set(ax, name, v)


async def read(tb: TB, values: dict) -> dict:
    return {k: await tb.get(k[0], k[1]) for k in values}


@cocotb.test()
async def save_comes_back_after_a_reset(dut):
    tb, flash = await start(dut)
    r = await tb.cmd("SAVE", op=0)
    assert (r["saved"], r["differs"]) == (0, 1), r
    await put(tb, VALUES_A)
    a = await read(tb, VALUES_A)
    t0 = get_sim_time("ns")
    r = await tb.cmd("SAVE", op=1)
    dut._log.info("SAVE answered after %.2f ms (model erase %.0f us, page program %.0f us)",
                  (get_sim_time("ns") - t0) / 1e6, ERASE_S * 1e6, PROGRAM_S * 1e6)
    assert (r["saved"], r["differs"], r["seq"]) == (1, 0, 1), r
    ops = {(op, addr - addr % SECTOR_BYTES) for op, addr in flash.log}
    assert ops == {("erase", P.STORE["slot_a"]), ("program", P.STORE["slot_a"])}, flash.log
    await tb.set(0, "KP_UNM_RAD", 123_000)
    assert (await tb.cmd("SAVE", op=0))["differs"] == 1
    await boot(tb)
    assert await read(tb, VALUES_A) == a
    r = await tb.cmd("SAVE", op=0)
    assert (r["saved"], r["differs"], r["seq"]) == (1, 0, 1), r
    # the next save goes to the other sector
    await put(tb, VALUES_B)
    n = len(flash.log)
    assert (await tb.cmd("SAVE", op=1))["seq"] == 2
    assert {addr - addr % SECTOR_BYTES for _, addr in flash.log[n:]} == {P.STORE["slot_b"]}, flash.log[n:]


@cocotb.test()
async def power_loss_in_a_save_keeps_the_old_copy_or_the_whole_new_one(dut):
    tb, flash = await start(dut)
    await put(tb, VALUES_A)
    await tb.cmd("SAVE", op=1)
    a = await read(tb, VALUES_A)
    pages = -(-(4 * (3 + (1 + P.AXIS_COUNT) * len(P.PARAMS) + 1)) // P.STORE["page_bytes"])
    cases = [(k, True) for k in range(1 + pages)] + [(pages, False)]     # each write cut in its middle; after the last
    b = None
    for write, during in cases:
        await put(tb, VALUES_B)
        if b is None:                              # what the firmware makes of them: the same every time
            b = await read(tb, VALUES_B)
        flash.cut(flash.writes + write, during)
        await tb.cmd("SAVE", expect=None, op=1)   # the power is gone: whatever the firmware thinks
        assert not flash.powered
        flash.power_on()
        await boot(tb)
        got = await read(tb, VALUES_A)
        whole = write == pages and not during
        what = f"power lost {'during' if during else 'after'} write {write} (0 = the erase)"
        dut._log.info("%s: the board starts with %s", what, "the new copy" if got == b else "the old copy")
        assert got == (b if whole else a), f"{what}: {got}"
        if whole:                                  # the new copy is now the old one for the next case
            await put(tb, VALUES_A)
            await tb.cmd("SAVE", op=1)


#: every cocotb test of this module (what @cocotb.test() makes of a function has one type)
CASES = [n for n, v in list(globals().items()) if type(v) is type(save_comes_back_after_a_reset)]


@pytest.mark.parametrize("case", CASES)
@pytest.mark.parametrize("sim", ["verilator"])
def test_firmware_store(sim, case):
    """One cocotb test per pytest test: they share test_firmware's build and run at once."""
    from torqueloop.flow.simrun import run, sims_for
    from torqueloop.flow.tb_images import servo_tb_image
    if sim not in sims_for("soc"):
        pytest.skip(f"{sim} not selected")
    img = servo_tb_image(KEY)
    run("soc", sim, "test_firmware_store",
        parameters={"RAM_INIT": f'"{img.ram_hex}"', "ROM_INIT": f'"{img.rom_hex}"'}, testcase=case)
