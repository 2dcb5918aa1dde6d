# SPDX-License-Identifier: MIT
"""reset_sync: assertion with no clock running, release after STAGES edges."""

import random

import cocotb
import pytest
from cocotb.clock import Clock
from cocotb.triggers import FallingEdge, ReadOnly, RisingEdge, Timer

from torqueloop.oracles.sync import ResetSyncModel
from torqueloop.flow.simrun import run, sims_for


@cocotb.test()
async def asserts_without_clock_releases_after_stages(dut):
    stages = int(dut.STAGES.value)
    model = ResetSyncModel(stages)
    clk = Clock(dut.clk, 20, unit="ns")

    # No clock yet: reset must still assert, combinationally through the flops' async input.
    dut.clk.value = 0
    dut.arst_n.value = 0
    await Timer(5, unit="ns")
    assert int(dut.rst_out.value) == 1, "reset did not assert without a clock"

    clk_task = cocotb.start_soon(clk.start())
    for trial in range(50):
        await FallingEdge(dut.clk)
        dut.arst_n.value = 1
        model.release()
        hold = random.randint(0, stages + 3)
        for _ in range(hold):
            await RisingEdge(dut.clk)
            model.clock()
            await ReadOnly()
            assert int(dut.rst_out.value) == model.rst_out, f"trial {trial}: release timing"
        # Assert again mid-cycle, away from any edge: output must follow at once.
        await Timer(random.randint(3, 7), unit="ns")
        dut.arst_n.value = 0
        model.assert_reset()
        await Timer(1, unit="ns")
        assert int(dut.rst_out.value) == 1, f"trial {trial}: async assertion"
    clk_task.cancel()


@pytest.mark.parametrize("stages", [2, 3])
@pytest.mark.parametrize("sim", sims_for("reset_sync"))
def test_reset_sync(sim, stages):
    run("reset_sync", sim, "test_reset_sync", parameters={"STAGES": stages})
