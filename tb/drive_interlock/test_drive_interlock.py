# SPDX-License-Identifier: MIT
"""drive_interlock: no bridge input passes unless armed; stop and faults disarm."""

import random

import cocotb
import pytest
from cocotb.clock import Clock
from cocotb.triggers import ClockCycles, FallingEdge, ReadOnly, RisingEdge

from torqueloop.oracles.drive_interlock import DriveInterlockModel, InterlockInputs
from torqueloop.flow.simrun import run, sims_for


def _apply(dut, i: InterlockInputs) -> None:
    dut.estop.value = int(i.estop)
    dut.arm_sw.value = int(i.arm_sw)
    dut.fault.value = i.fault
    dut.alive.value = int(i.alive)
    dut.rpwm_in.value = i.rpwm
    dut.lpwm_in.value = i.lpwm
    dut.r_en_in.value = i.r_en
    dut.l_en_in.value = i.l_en


def _check(dut, exp, where: str) -> None:
    got = {
        "rpwm": int(dut.rpwm_out.value), "lpwm": int(dut.lpwm_out.value),
        "r_en": int(dut.r_en_out.value), "l_en": int(dut.l_en_out.value),
        "armed": bool(int(dut.armed.value)), "tripped": bool(int(dut.tripped.value)),
        "fault_latched": int(dut.fault_latched.value),
    }
    want = {k: getattr(exp, k) for k in got}
    assert got == want, f"{where}: got {got}, model {want}"


async def _reset(dut, model: DriveInterlockModel, inputs: InterlockInputs) -> None:
    _apply(dut, inputs)
    dut.rst.value = 1
    await ClockCycles(dut.clk, 2)
    await ReadOnly()
    _check(dut, model.reset(), "in reset")
    await FallingEdge(dut.clk)
    dut.rst.value = 0


async def _step(dut, model: DriveInterlockModel, i: InterlockInputs, where: str):
    _apply(dut, i)
    await RisingEdge(dut.clk)
    exp = model.clock(i)
    await ReadOnly()
    _check(dut, exp, where)
    await FallingEdge(dut.clk)
    return exp


@cocotb.test()
async def stays_safe_until_armed_and_follows_model(dut):
    axes = int(dut.AXES.value)
    full = (1 << axes) - 1
    model = DriveInterlockModel(axes=axes, fault_filter_clks=int(dut.FAULT_FILTER_CLKS.value))
    cocotb.start_soon(Clock(dut.clk, 20, unit="ns").start())

    # Switch already up at reset, SoC asking for full drive: nothing may move.
    demand = InterlockInputs(arm_sw=True, rpwm=full, lpwm=0, r_en=full, l_en=full)
    await _reset(dut, model, demand)
    for c in range(20):
        exp = await _step(dut, model, demand, f"switch up at reset, cycle {c}")
        assert not exp.armed and exp.r_en == 0
    # Down, up: armed; demand passes one clock later.
    await _step(dut, model, InterlockInputs(arm_sw=False, rpwm=full, r_en=full, l_en=full), "switch down")
    await _step(dut, model, demand, "switch up")
    exp = await _step(dut, model, demand, "armed")
    assert exp.armed and exp.r_en == full and exp.rpwm == full, "arming did not pass the demand"
    # E-stop held: everything off, stays off after release until re-armed.
    for c in range(10):
        exp = await _step(dut, model, InterlockInputs(estop=True, arm_sw=True, rpwm=full, r_en=full, l_en=full),
                          f"estop {c}")
    assert not exp.armed and exp.tripped and exp.rpwm == 0 and exp.r_en == 0
    for c in range(10):
        exp = await _step(dut, model, demand, f"estop released {c}")
        assert not exp.armed and exp.r_en == 0

    # Liveness: the SoC's watchdog expires (firmware hung) - off at once and tripped;
    # alive again, the switch still has to be moved down and up.
    await _step(dut, model, InterlockInputs(arm_sw=False), "switch down")
    await _step(dut, model, demand, "switch up")
    exp = await _step(dut, model, demand, "armed again")
    assert exp.armed
    dead = InterlockInputs(arm_sw=True, alive=False, rpwm=full, r_en=full, l_en=full)
    exp = await _step(dut, model, dead, "watchdog expired")
    assert not exp.armed and exp.tripped
    exp = await _step(dut, model, dead, "watchdog expired, next clock")
    assert exp.rpwm == 0 and exp.r_en == 0
    await _step(dut, model, InterlockInputs(arm_sw=False, alive=False), "switch down while dead")
    exp = await _step(dut, model, dead, "switch up while dead")
    assert not exp.armed, "armed with the watchdog expired"
    for c in range(3):
        exp = await _step(dut, model, demand, f"alive again {c}")
        assert not exp.armed, "alive again re-armed without the switch"

    # Random phase: switch moves, stop presses, fault bursts of random length.
    arm_sw, estop, fault_bits, alive = True, False, 0, True
    armed_cycles = c = 0
    # At least 2000 cycles, and on until both states have had 100 (a seed whose
    # switch sat down for most of 2000 cycles proved little about the armed state)
    while c < 2000 or (min(armed_cycles, c - armed_cycles) < 100 and c < 20_000):
        c += 1
        if random.random() < 0.02:
            arm_sw = not arm_sw
        if random.random() < 0.01:
            estop = not estop if estop or random.random() < 0.3 else estop
        if random.random() < 0.03:
            fault_bits = random.getrandbits(axes) if random.random() < 0.3 else 0
        # the watchdog expires now and then and is soon fed again
        if alive and random.random() < 0.002:
            alive = False
        elif not alive and random.random() < 0.05:
            alive = True
        i = InterlockInputs(estop=estop, arm_sw=arm_sw, fault=fault_bits, alive=alive,
                            rpwm=random.getrandbits(axes), lpwm=random.getrandbits(axes),
                            r_en=random.getrandbits(axes), l_en=random.getrandbits(axes))
        exp = await _step(dut, model, i, f"random cycle {c}")
        armed_cycles += exp.armed
    # The random phase must have exercised both states, or it proved nothing.
    assert min(armed_cycles, c - armed_cycles) >= 100, f"armed in {armed_cycles} of {c} cycles"
    dut._log.info("armed in %d of %d random cycles", armed_cycles, c)


@pytest.mark.parametrize("sim", sims_for("drive_interlock"))
def test_drive_interlock(sim):
    run("drive_interlock", sim, "test_drive_interlock", parameters={"AXES": 2, "FAULT_FILTER_CLKS": 4})
