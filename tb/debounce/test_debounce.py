# SPDX-License-Identifier: MIT
"""debounce: random bouncing inputs against the reference model
(torqueloop/oracles/sync.py DebounceModel): bursts of glitches shorter than
STABLE_CLKS never reach the output, held levels do, after exactly
STABLE_CLKS clocks; reset holds the output at RESET_VAL."""

import random

import cocotb
import pytest
from cocotb.clock import Clock
from cocotb.triggers import FallingEdge, ReadOnly, RisingEdge

from torqueloop.flow.simrun import run, sims_for
from torqueloop.oracles.sync import DebounceModel

import tbutil


@cocotb.test()
async def follows_model_with_bouncing_input(dut):
    width, stable, reset_val = int(dut.WIDTH.value), int(dut.STABLE_CLKS.value), int(dut.RESET_VAL.value)
    model = DebounceModel(width, stable, reset_val)
    cocotb.start_soon(Clock(dut.clk, 20, unit="ns").start())
    dut.sync_in.value = 0
    await tbutil.reset_then_check(dut, "q", model.reset_word)
    level, changes = model.reset_word, 0
    for cycle in range(4000):
        # hold a level for a while, then bounce: runs both shorter and longer than STABLE_CLKS
        if random.random() < 1 / (stable + 2):
            level = random.getrandbits(width)
        cur = level ^ (random.getrandbits(width) if random.random() < 0.15 else 0)
        dut.sync_in.value = cur
        await RisingEdge(dut.clk)
        before = model.q
        expected = model.clock(cur)
        changes += expected != before
        await ReadOnly()
        assert int(dut.q.value) == expected, f"cycle {cycle}: q={int(dut.q.value):#x}, model {expected:#x}"
        await FallingEdge(dut.clk)
    assert changes > 5, "the run never passed a change: stimulus too bouncy"


@pytest.mark.parametrize("params", [{"WIDTH": 1, "STABLE_CLKS": 1, "RESET_VAL": 0},
                                    {"WIDTH": 2, "STABLE_CLKS": 7, "RESET_VAL": 1}], ids=["w1s1r0", "w2s7r1"])
@pytest.mark.parametrize("sim", sims_for("debounce"))
def test_debounce(sim, params):
    run("debounce", sim, "test_debounce", parameters=params)
