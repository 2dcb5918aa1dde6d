# SPDX-License-Identifier: MIT
"""freq_div: tick period measured on the pin for divisors 0, 1, 2 .. large,
the reset default (eq. 4 Count_max), and a seeded random stream of divisor
writes at random times compared with the reference model every clock."""

import random

import cocotb
import pytest
from cocotb.clock import Clock
from cocotb.triggers import FallingEdge

from torqueloop.oracles.freq_div import FreqDivModel, FreqDivParams, effective_div
from torqueloop.flow.simrun import run, sims_for


class TB:
    """Drives inputs and reads outputs at falling edges: each step() is one rising edge."""

    def __init__(self, dut) -> None:
        self.dut = dut
        self.p = FreqDivParams(div_bits=int(dut.DIV_BITS.value), default_div=int(dut.DEFAULT_DIV.value))
        self.model = FreqDivModel(self.p)
        self.cycle = 0
        cocotb.start_soon(Clock(dut.clk, 20, unit="ns").start())

    async def step(self, rst: int = 0, div_we: int = 0, div_in: int = 0) -> int:
        """One clock with these inputs; checks tick and div against the model; returns tick."""
        d = self.dut
        d.rst.value = rst
        d.div_we.value = div_we
        d.div_in.value = div_in
        await FallingEdge(d.clk)
        self.cycle += 1
        want_tick, want_div = self.model.clock(rst, div_we, div_in)
        tick, div = int(d.tick.value), int(d.div.value)
        assert (tick, div) == (want_tick, want_div), \
            f"clock {self.cycle}: tick={tick} div={div}, model tick={want_tick} div={want_div}"
        return tick

    async def reset(self) -> None:
        await FallingEdge(self.dut.clk)
        for _ in range(2):
            await self.step(rst=1)

    async def tick_periods(self, n: int, limit: int) -> list[int]:
        """Clocks between the next n+1 ticks, counted on the pin (inputs idle)."""
        gaps, since, seen = [], 0, False
        for _ in range(limit):
            since += 1
            if await self.step():
                if seen:
                    gaps.append(since)
                    if len(gaps) == n:
                        return gaps
                seen, since = True, 0
        raise AssertionError(f"only {len(gaps)} tick periods in {limit} clocks")


@cocotb.test()
async def reset_default_is_eq4_count_max(dut):
    tb = TB(dut)
    await tb.reset()
    assert int(dut.div.value) == tb.p.default_div
    gaps = await tb.tick_periods(3, 4 * tb.p.default_div + 8)
    assert gaps == [tb.p.default_div] * 3, f"tick period {gaps}, Count_max {tb.p.default_div}"


@cocotb.test()
async def tick_period_equals_divisor(dut):
    tb = TB(dut)
    await tb.reset()
    # The register's maximum is measured with the narrow build; the 16-bit one
    # stops at the 50 Hz Count_max to keep the run short.
    big = min(tb.p.div_max, 977)
    for div in sorted({0, 1, 2, 3, 7, 109, big, random.randint(2, big)}):
        await tb.step(div_we=1, div_in=div)
        gaps = await tb.tick_periods(3, 5 * effective_div(div) + 8)
        assert gaps == [effective_div(div)] * 3, f"divisor {div}: tick gaps {gaps}"


@cocotb.test()
async def lowering_divisor_below_count_ticks_next_clock(dut):
    """A smaller divisor must not wait for a counter wrap-around (2^DIV_BITS clocks)."""
    tb = TB(dut)
    await tb.reset()
    big = min(tb.p.div_max, 977)
    await tb.step(div_we=1, div_in=big)
    await tb.tick_periods(1, 2 * big + 4)
    for _ in range(big // 2):
        assert not await tb.step()
    await tb.step(div_we=1, div_in=2)
    assert await tb.step(), "no tick on the clock after lowering the divisor below the count"


@cocotb.test()
async def random_divisor_writes_follow_model(dut):
    tb = TB(dut)
    await tb.reset()
    div_max = tb.p.div_max
    for _ in range(3000):
        r = random.random()
        if r < 0.02:
            await tb.step(div_we=1, div_in=random.randint(0, min(div_max, 40)))
        elif r < 0.025:
            await tb.step(div_we=1, div_in=random.randint(0, div_max))
        elif r < 0.03:
            await tb.step(rst=1)
        else:
            # div_in without div_we must be ignored
            await tb.step(div_in=random.randint(0, div_max))


PARAMS = {
    "default": {},
    # Narrow register: an 8-bit divisor, its largest value after reset.
    "narrow": {"DIV_BITS": 8, "DEFAULT_DIV": 255},
}


# Every simulator runs the defaults; the narrow build skips Verilator, whose
# C++ build (~15 CPU-s) is most of this bench's cost in make test.
CASES = [(sim, "default") for sim in sims_for("freq_div")] + \
        [(sim, "narrow") for sim in sims_for("freq_div") if sim != "verilator"]


@pytest.mark.parametrize("sim, params", CASES, ids=[f"{s}-{p}" for s, p in CASES])
def test_freq_div(sim, params):
    run("freq_div", sim, "test_freq_div", parameters=PARAMS[params])
