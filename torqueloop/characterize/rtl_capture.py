# SPDX-License-Identifier: MIT
"""The simulated characterisation bench, RTL side (a cocotb module, run by
:func:`torqueloop.characterize.simbench.rtl_waveforms`): freq_div +
pwm_torque (char_bench_top.v, this folder) driven with Count_max and duty
settings; the IBT-2 pins are watched and each setting's pin waveform over
one whole PWM period is returned (times of every pin change).  simbench
feeds those waveforms to the plant's dynamometer model.

The ``capture`` test reads a job (JSON list of settings) from
$CHAR_BENCH_JOB and writes the waveforms to $CHAR_BENCH_RESULT.
"""

from __future__ import annotations

import json
import os
from pathlib import Path

import cocotb
from cocotb.clock import Clock
from cocotb.simtime import get_sim_time
from cocotb.triggers import ClockCycles, FallingEdge, First, ReadOnly, RisingEdge

CLK_NS = 20  # CLOCK_50
PINS = ("rpwm", "lpwm", "r_en", "l_en")


def _pins(dut) -> tuple[int, ...]:
    return tuple(int(getattr(dut, p).value) for p in PINS)


def _now_ps() -> int:
    return int(round(get_sim_time(unit="ps")))


async def _one_period(dut) -> dict:
    """Pin waveform from one period start to the next."""
    await RisingEdge(dut.period_start)
    await ReadOnly()
    t0 = _now_ps()
    segs: list[list[int]] = [[0, *_pins(dut)]]
    while True:
        await First(RisingEdge(dut.period_start), *(getattr(dut, p).value_change for p in PINS))
        await ReadOnly()
        t = _now_ps()
        if t > t0 and int(dut.period_start.value) == 1:
            break
        p = _pins(dut)
        if list(p) != segs[-1][1:]:
            segs.append([t - t0, *p])
    return {"period_ps": t - t0, "segments_ps": segs}


@cocotb.test()
async def capture(dut):
    job = json.loads(Path(os.environ["CHAR_BENCH_JOB"]).read_text())
    cocotb.start_soon(Clock(dut.clk, CLK_NS, unit="ns").start())
    for name in ("div_we", "div_in", "cmd", "pw0", "pw_max", "enable"):   # in reset, everything off
        getattr(dut, name).value = 0
    dut.rst.value = 1
    await ClockCycles(dut.clk, 4)
    await FallingEdge(dut.clk)
    dut.rst.value = 0
    dut.enable.value = 1
    out = []
    for k, s in enumerate(job):
        # The divisor applies at once (the running period finishes at the new
        # tick rate); the duty is double-buffered and taken at a period start
        # from inputs at least PIPE_CLOCKS = 3 clocks old.  So: write, wait 4
        # clocks, and record from the next period start to the one after.
        await FallingEdge(dut.clk)
        dut.div_in.value = s["count_max"]
        dut.div_we.value = 1
        dut.cmd.value = s["cmd"]
        dut.pw0.value = s.get("pw0", 0)
        dut.pw_max.value = s.get("pw_max", 1023)
        await FallingEdge(dut.clk)
        dut.div_we.value = 0
        await ClockCycles(dut.clk, 4)
        rec = await _one_period(dut)
        assert int(dut.div.value) == s["count_max"], f"setting {k}: divisor register reads {int(dut.div.value)}"
        out.append({**s, **rec})
        dut._log.info(
            "setting %d/%d: count_max %d cmd %d -> period %.1f us, %d pin changes",
            k + 1, len(job), s["count_max"], s["cmd"], rec["period_ps"] / 1e6, len(rec["segments_ps"]),
        )
    Path(os.environ["CHAR_BENCH_RESULT"]).write_text(json.dumps(out))
