# SPDX-License-Identifier: MIT
"""quad_decoder: every output compared with the clock-level reference model
on every clock, plus the end-to-end count of the encoder waveform generator
(torqueloop/oracles/quad_decoder.py).  Directed cases first, then seeded random
streams with glitches shorter and longer than the filter, illegal
transitions and index pulses, up to the stated maximum count rate."""

from __future__ import annotations

import random
from dataclasses import asdict

import cocotb
import pytest
from cocotb.clock import Clock
from cocotb.triggers import FallingEdge

from torqueloop.oracles.quad_decoder import (
    GRAY_UP,
    QuadDecoderModel,
    QuadInputs,
    QuadSettings,
    encoder_stream,
    max_rejected_glitch_clocks,
    min_accepted_pulse_clocks,
    min_state_clocks,
    to_signed32,
)
from torqueloop.flow.simrun import run, sims_for

import tbutil

OUTPUTS = ("position", "dir", "illegal_count", "illegal_flag", "index_pos", "index_seen",
           "index_armed", "timestamp", "last_edge_time", "edge_interval", "enc_filtered")
STROBES = ("pos_load", "illegal_clear", "index_arm")


class TB:
    """Owns the clock, the pins and the model; one call of :meth:`tick` is one clock."""

    def __init__(self, dut) -> None:
        self.dut = dut
        self.model = QuadDecoderModel(ts_bits=len(dut.timestamp), illegal_bits=len(dut.illegal_count))
        self.inp = QuadInputs()
        self.handles = {name: getattr(dut, name) for name in OUTPUTS}
        self.cycle = 0
        cocotb.start_soon(Clock(dut.clk, 20, unit="ns").start())

    def _drive(self) -> None:
        v = asdict(self.inp)   # named as the core's ports, but the encoder pins
        tbutil.drive(self.dut, enc_a=v.pop("a"), enc_b=v.pop("b"), enc_z=v.pop("z"), **v)

    async def tick(self, **change: int) -> None:
        """Apply pins/commands (strobes last one clock), clock once, compare all outputs."""
        for k, v in change.items():
            setattr(self.inp, k, v)
        self._drive()
        await FallingEdge(self.dut.clk)
        self.model.clock(self.inp)
        self.cycle += 1
        for s in STROBES:
            setattr(self.inp, s, 0)
        if self.inp.rst:
            return
        want = self.model.outputs()
        for name, h in self.handles.items():
            got = int(h.value)
            assert got == want[name], (
                f"clock {self.cycle}: {name} = {got:#x}, model {want[name]:#x} "
                f"(sample_div={self.inp.sample_div}, filter_len={self.inp.filter_len})")

    async def reset(self, a: int = 0, b: int = 0, settings: QuadSettings = QuadSettings(0, 1)) -> None:
        self.inp.sample_div, self.inp.filter_len = settings.sample_div, settings.filter_len
        for _ in range(4):
            await self.tick(rst=1, a=a, b=b, z=0)
        await self.tick(rst=0)

    async def pins(self, seq) -> None:
        for a, b, z in seq:
            await self.tick(a=a, b=b, z=z)

    async def hold(self, n: int) -> None:
        for _ in range(n):
            await self.tick()

    @property
    def position(self) -> int:
        return to_signed32(int(self.dut.position.value))


async def start(dut) -> TB:
    tb = TB(dut)
    await FallingEdge(dut.clk)
    return tb


@cocotb.test()
async def reset_at_any_shaft_position_makes_no_count(dut):
    """The filter loads the pins during reset: no count or illegal flag at start-up."""
    tb = await start(dut)
    for a, b in GRAY_UP:
        await tb.reset(a, b, QuadSettings(sample_div=1, filter_len=3))
        await tb.hold(30)
        assert tb.position == 0 and int(dut.illegal_flag.value) == 0, f"start-up at A={a} B={b}"


@cocotb.test()
async def directed_counting_filter_illegal_index_load(dut):
    s = QuadSettings(sample_div=2, filter_len=4)
    tb = await start(dut)
    await tb.reset(0, 0, s)
    settle = min_accepted_pulse_clocks(s) + 3 * s.sample_clocks

    # Four counts up (A leads B), then back down.
    for a, b in GRAY_UP[1:] + GRAY_UP[:1]:
        await tb.pins([(a, b, 0)] * settle)
    assert tb.position == 4 and int(dut.dir.value) == 1
    interval = int(dut.edge_interval.value)
    assert interval == settle, f"edge_interval {interval}, steps were {settle} clocks apart"
    for a, b in reversed(GRAY_UP):
        await tb.pins([(a, b, 0)] * settle)
    assert tb.position == 0 and int(dut.dir.value) == 0

    # A glitch covering at most N - 1 samples is ignored; N samples count (one step and back).
    edges_before = int(dut.last_edge_time.value)
    await tb.pins([(1, 0, 0)] * max_rejected_glitch_clocks(s) + [(0, 0, 0)] * settle)
    assert int(dut.last_edge_time.value) == edges_before, "short glitch was counted"
    await tb.pins([(1, 0, 0)] * min_accepted_pulse_clocks(s) + [(0, 0, 0)] * settle)
    assert tb.position == 0 and int(dut.last_edge_time.value) != edges_before, "long pulse not seen"

    # Illegal transition: both channels at once; no count, flagged, counted, clearable.
    await tb.pins([(1, 1, 0)] * settle)
    assert tb.position == 0 and int(dut.illegal_flag.value) == 1 and int(dut.illegal_count.value) == 1
    await tb.tick(illegal_clear=1)
    assert int(dut.illegal_flag.value) == 0 and int(dut.illegal_count.value) == 0

    # Index: ignored until armed, then latches the position once.
    await tb.pins([(1, 1, 1)] * settle + [(1, 1, 0)] * settle)
    assert int(dut.index_seen.value) == 0
    await tb.tick(index_arm=1)
    await tb.pins([(0, 1, 0)] * settle)      # 11 -> 01 is one count up -> 1
    await tb.pins([(0, 1, 1)] * settle + [(0, 1, 0)] * settle)
    assert int(dut.index_seen.value) == 1 and to_signed32(int(dut.index_pos.value)) == 1

    # Load, and the 32-bit wrap counts as one step.
    await tb.tick(pos_load=1, pos_load_val=0x7FFF_FFFF)
    await tb.pins([(0, 0, 0)] * settle)       # up: 01 -> 00
    assert int(dut.position.value) == 0x8000_0000


async def random_run(dut, settings: list[tuple[QuadSettings, bool]], n_events: int) -> None:
    tb = await start(dut)
    for s, max_rate in settings:
        stream = encoder_stream(random, s, n_events, start_phase=random.randrange(4), max_rate=max_rate)
        a, b, _ = stream.pins[0]
        await tb.reset(a, b, s)
        await tb.pins(stream.pins)
        dut._log.info("sample_div=%d N=%d max_rate=%s: %d steps (min state %d clocks), %d short and "
                      "%d long glitches, %d illegal, %d index; position %d",
                      s.sample_div, s.filter_len, max_rate, stream.n_steps, min_state_clocks(s),
                      stream.n_glitches_short, stream.n_glitches_long, stream.n_illegal,
                      stream.n_index, tb.position)
        assert tb.position == stream.expected_count, (
            f"end-to-end: position {tb.position}, encoder moved {stream.expected_count}")
        assert int(dut.illegal_count.value) == stream.n_illegal


@cocotb.test()
async def random_streams_up_to_max_rate(dut):
    await random_run(dut, [
        (QuadSettings(sample_div=0, filter_len=1), True),
        (QuadSettings(sample_div=0, filter_len=3), True),
        (QuadSettings(sample_div=1, filter_len=6), False),
        (QuadSettings(sample_div=2, filter_len=15), True),
        (QuadSettings(sample_div=0, filter_len=0), False),
    ], n_events=500)


@pytest.mark.parametrize("sim", sims_for("quad_decoder"))
def test_quad_decoder(sim):
    run("quad_decoder", sim, "test_quad_decoder")
