# SPDX-License-Identifier: MIT
"""sync_2ff: random asynchronous input against the two-flop reference model,
with inputs changing at random times within the clock period."""

import random

import cocotb
import pytest
from cocotb.clock import Clock
from cocotb.triggers import FallingEdge, ReadOnly, RisingEdge, Timer

from torqueloop.oracles.sync import Sync2ffModel
from torqueloop.flow.simrun import run, sims_for

import tbutil


@cocotb.test()
async def follows_model_with_random_async_input(dut):
    width = int(dut.WIDTH.value)
    reset_val = int(dut.RESET_VAL.value)
    model = Sync2ffModel(width, reset_val)
    cocotb.start_soon(Clock(dut.clk, 20, unit="ns").start())

    dut.async_in.value = model.reset_word
    await tbutil.reset_then_check(dut, "sync_out", model.reset_word)

    current = model.reset_word
    for cycle in range(2000):
        # Change the input at a random point of the cycle, never at the edge itself.
        await Timer(random.randint(1, 18), unit="ns")
        if random.random() < 0.4:
            current = random.getrandbits(width)
            dut.async_in.value = current
        await RisingEdge(dut.clk)
        expected = model.clock(current)
        await ReadOnly()
        got = int(dut.sync_out.value)
        assert got == expected, f"cycle {cycle}: sync_out={got:#x}, model {expected:#x}"
        await FallingEdge(dut.clk)


@pytest.mark.parametrize("params", [{"WIDTH": 1, "RESET_VAL": 0}, {"WIDTH": 4, "RESET_VAL": 1}],
                         ids=["w1r0", "w4r1"])
@pytest.mark.parametrize("sim", sims_for("sync_2ff"))
def test_sync_2ff(sim, params):
    run("sync_2ff", sim, "test_sync_2ff", parameters=params)
