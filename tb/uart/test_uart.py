# SPDX-License-Identifier: MIT
"""uart (top: rx, tx, FIFOs, flow control) against cocotbext-uart, an
independent bus model, and the reference model in torqueloop/oracles/uart.py.

Fast links (16-100 clocks per bit) keep simulated time short; one case runs
the real setting (50 MHz, baud_div = 0 -> 115200).  Random bytes and the
timing of reads and writes come from cocotb's seeded `random` (seed printed
at start; rerun with COCOTB_RANDOM_SEED)."""

from __future__ import annotations

import random

import cocotb
import pytest
from cocotb.clock import Clock
from cocotb.triggers import ClockCycles, FallingEdge, Timer, ValueChange, with_timeout
from cocotb.utils import get_sim_time
from cocotbext.uart import UartSink, UartSource

from torqueloop.oracles.uart import (
    LineDecoder,
    RxFifoModel,
    UartParams,
    baud_of,
    effective_div,
    frame_segments,
)
from torqueloop.flow.simrun import run, sims_for

import tbutil

CLK_NS = 20


def model_baud(bit_ns: float) -> float:
    """Baud to give cocotbext-uart so that its int(1e9 / baud) ns bit time is ``bit_ns``."""
    return 1e9 / (round(bit_ns) + 0.4)


class TB:
    def __init__(self, dut) -> None:
        self.dut = dut
        self.p = UartParams(clk_hz=int(dut.CLK_HZ.value), default_baud=int(dut.DEFAULT_BAUD.value),
                            fifo_depth=int(dut.FIFO_DEPTH.value), rts_slack=int(dut.RTS_SLACK.value))
        self.pulses = {"frame_error": 0, "break_detect": 0, "overrun_error": 0}
        self.rts_violations: list[str] = []
        cocotb.start_soon(Clock(dut.clk, CLK_NS, unit="ns").start())

    async def reset(self, baud_div: int = 0, flow_en: int = 0) -> None:
        d = self.dut
        tbutil.drive(d, rst=1, baud_div=baud_div, flow_en=flow_en, s_tx_data=0, s_tx_valid=0, m_rx_ready=0,
                     overrun_clear=0, rxd=1, cts_n=0)
        await ClockCycles(d.clk, 4)
        await FallingEdge(d.clk)
        d.rst.value = 0

    def bit_ns(self, baud_div: int) -> float:
        return (effective_div(baud_div, self.p) + 1) * CLK_NS

    async def write(self, data: bytes, stall: float = 0.0) -> None:
        """Push bytes into the TX FIFO through valid/ready (random gaps if stall > 0)."""
        d = self.dut
        for b in data:
            while stall and random.random() < stall:
                d.s_tx_valid.value = 0
                await FallingEdge(d.clk)
            d.s_tx_data.value = b
            d.s_tx_valid.value = 1
            while True:
                # ready depends on registers only: its value now holds at the next edge
                ready = int(d.s_tx_ready.value)
                await FallingEdge(d.clk)
                if ready:
                    break
        d.s_tx_valid.value = 0

    async def drain(self, model: RxFifoModel | None = None, stall: float = 0.0) -> bytes:
        """Read the RX FIFO until empty; check each byte against the model's FIFO."""
        d = self.dut
        out = bytearray()
        await FallingEdge(d.clk)
        while int(d.m_rx_valid.value):
            if stall and random.random() < stall:
                d.m_rx_ready.value = 0
                await FallingEdge(d.clk)
                continue
            got = int(d.m_rx_data.value)
            if model is not None:
                want = model.read()
                assert got == want, f"rx byte {len(out)}: {got:#04x}, model {want:#04x}"
            out.append(got)
            d.m_rx_ready.value = 1
            await FallingEdge(d.clk)
            d.m_rx_ready.value = 0
            await FallingEdge(d.clk)
        return bytes(out)

    async def monitor(self, flow_en: bool) -> None:
        """Count one-clock status pulses; check rts_n against the RX level every clock."""
        d = self.dut
        prev_level = 0
        while True:
            await FallingEdge(d.clk)
            for k in self.pulses:
                self.pulses[k] += int(getattr(d, k).value)
            level = int(d.rx_level.value)
            want = int(flow_en and prev_level >= self.p.rts_level)   # registered: one clock later
            if int(d.rts_n.value) != want:
                self.rts_violations.append(f"rts_n={int(d.rts_n.value)} with level {prev_level}")
            prev_level = level

    async def record_txd(self, changes: list[tuple[float, int]]) -> None:
        """Log (time in clocks, level) of every txd change, for the reference decoder."""
        changes.append((get_sim_time("ns") / CLK_NS, int(self.dut.txd.value)))
        while True:
            await ValueChange(self.dut.txd)
            changes.append((get_sim_time("ns") / CLK_NS, int(self.dut.txd.value)))

    async def drive_line(self, segments: list[tuple[int, float]]) -> None:
        for level, clocks in segments:
            self.dut.rxd.value = level
            await Timer(round(clocks * CLK_NS), unit="ns")
        self.dut.rxd.value = 1


async def loopback(dut, baud_div: int, mismatch: float, n_bytes: int) -> None:
    """TX bytes to a cocotbext-uart sink at the exact rate; RX bytes from a source off by ``mismatch``."""
    tb = TB(dut)
    await tb.reset(baud_div)
    bit = tb.bit_ns(baud_div)
    sink = UartSink(dut.txd, baud=model_baud(bit))
    source = UartSource(dut.rxd, baud=model_baud(bit / (1 + mismatch)))
    dut._log.info("baud_div %d: %.0f baud, source %+.1f %%", baud_div,
                  baud_of(effective_div(baud_div, tb.p), tb.p.clk_hz), 100 * mismatch)
    txd_changes: list[tuple[float, int]] = []
    cocotb.start_soon(tb.record_txd(txd_changes))
    tx_data = bytes(random.getrandbits(8) for _ in range(n_bytes))
    rx_data = bytes(random.getrandbits(8) for _ in range(n_bytes))
    received = bytearray()
    frame_ns = 10 * bit * (1 + abs(mismatch))
    # Chunks no larger than the FIFO, so no overrun here: that has its own test.
    for start in range(0, n_bytes, tb.p.fifo_depth // 2):
        tx_chunk = tx_data[start:start + tb.p.fifo_depth // 2]
        rx_chunk = rx_data[start:start + tb.p.fifo_depth // 2]
        await source.write(rx_chunk)
        await tb.write(tx_chunk, stall=0.3)
        await with_timeout(source.wait(), frame_ns * (len(rx_chunk) + 2), "ns")
        await Timer(bit * 2, unit="ns")
        received += await tb.drain(stall=0.3)
    got_tx = bytearray()
    while len(got_tx) < n_bytes:
        await with_timeout(sink.wait(), frame_ns * (n_bytes + 2), "ns")
        got_tx += sink.read_nowait()
    assert bytes(got_tx) == tx_data, f"TX: sink got {got_tx.hex()}, sent {tx_data.hex()}"
    # The sink ignores stop bits; the reference decoder checks them (and the bit timing).
    await Timer(2 * bit, unit="ns")
    segs = [(lvl, t1 - t0) for (t0, lvl), (t1, _) in zip(txd_changes, txd_changes[1:])]
    segs.append((txd_changes[-1][1], 20 * bit / CLK_NS))
    events = LineDecoder(effective_div(baud_div, tb.p)).decode(segs)
    assert [(e.kind, e.data) for e in events] == [("byte", b) for b in tx_data], f"txd decoded as {events}"
    assert bytes(received) == rx_data, f"RX: got {bytes(received).hex()}, source sent {rx_data.hex()}"
    assert int(dut.overrun_count.value) == 0


@cocotb.test()
@cocotb.parametrize(
    (("baud_div", "mismatch"),
     [(15, 0.0), (15, 0.02), (15, -0.02), (24, 0.02), (99, -0.02), (99, 0.0)]),
)
async def loopback_against_bus_model(dut, baud_div, mismatch):
    await loopback(dut, baud_div, mismatch, n_bytes=24)


@cocotb.test()
async def real_rate_115200_from_reset_default(dut):
    """baud_div = 0 at CLK_HZ = 50 MHz is 434 clocks per bit; a few bytes each way."""
    tb = TB(dut)
    assert effective_div(0, tb.p) == 433 and abs(baud_of(433, tb.p.clk_hz) / 115200 - 1) < 1e-4
    await loopback(dut, 0, 0.0, n_bytes=3)


@cocotb.test()
async def framing_error_break_and_glitch(dut):
    """Line waveforms from the reference model; its decoder says what must happen."""
    tb = TB(dut)
    div = 31
    await tb.reset(div)
    cocotb.start_soon(tb.monitor(flow_en=False))
    L = div + 1
    segs: list[tuple[int, float]] = [(1, 2 * L)]
    segs += frame_segments(0x5A, L)                       # good byte
    segs += [(1, L), (0, 4), (1, 2 * L)]                  # 4-clock glitch: not a start bit
    segs += frame_segments(0xA5, L, stop=0) + [(1, 2 * L)]  # framing error
    segs += [(0, 25 * L), (1, 3 * L)]                     # break, longer than two frames
    # good byte with a one-clock spike at the centre sample of every data bit
    for lvl in [0] + [(0xC3 >> k) & 1 for k in range(8)] + [1]:
        segs += [(lvl, L // 2), (lvl ^ 1, 1), (lvl, L - L // 2 - 1)]
    segs += [(1, 2 * L)]
    segs += frame_segments(0x00, L)                       # zero byte with a good stop: not a break
    segs += [(1, 2 * L)]
    events = LineDecoder(div).decode(segs)
    want_bytes = bytes(e.data for e in events if e.kind == "byte")
    assert want_bytes == bytes([0x5A, 0xC3, 0x00]), f"model decoded {events}"
    await tb.drive_line(segs)
    await ClockCycles(dut.clk, 4)
    got = await tb.drain()
    assert got == want_bytes, f"received {got.hex()}, model {want_bytes.hex()}"
    n_fe = sum(e.kind == "frame_error" for e in events)
    n_brk = sum(e.kind == "break" for e in events)
    assert (n_fe, n_brk) == (2, 1)
    assert tb.pulses["frame_error"] == n_fe, f"frame_error pulses {tb.pulses}"
    assert tb.pulses["break_detect"] == n_brk, f"break_detect pulses {tb.pulses}"


@cocotb.test()
async def overrun_counted_and_rts_threshold(dut):
    """The peer ignores RTS and sends FIFO_DEPTH + 3 bytes unread: 3 overruns; RTS
    rises at FIFO_DEPTH - RTS_SLACK; the first FIFO_DEPTH bytes are kept."""
    tb = TB(dut)
    div = 15
    await tb.reset(div, flow_en=1)
    cocotb.start_soon(tb.monitor(flow_en=True))
    model = RxFifoModel(tb.p)
    n = tb.p.fifo_depth + 3
    data = bytes(random.getrandbits(8) for _ in range(n))
    source = UartSource(dut.rxd, baud=model_baud(tb.bit_ns(div)))
    rts_seen = False
    for b in data:
        await source.write([b])
        await source.wait()
        await ClockCycles(dut.clk, div)      # past the stop bit's decision
        model.receive(b)
        await FallingEdge(dut.clk)
        assert int(dut.rx_level.value) == len(model.fifo)
        assert int(dut.rts_n.value) == model.rts_n(True), f"rts_n at level {len(model.fifo)}"
        rts_seen |= bool(model.rts_n(True))
    assert rts_seen
    assert int(dut.overrun_count.value) == model.overruns == 3
    assert tb.pulses["overrun_error"] == 3
    got = await tb.drain(model)
    assert got == data[:tb.p.fifo_depth]
    assert not tb.rts_violations, tb.rts_violations[:3]
    assert int(dut.rts_n.value) == 0, "rts_n must fall once the FIFO is read"
    dut.overrun_clear.value = 1
    await FallingEdge(dut.clk)
    dut.overrun_clear.value = 0
    await FallingEdge(dut.clk)
    assert int(dut.overrun_count.value) == 0


@cocotb.test()
async def cts_holds_tx_between_frames(dut):
    tb = TB(dut)
    div = 15
    bit = tb.bit_ns(div)
    await tb.reset(div, flow_en=1)
    sink = UartSink(dut.txd, baud=model_baud(bit))
    dut.cts_n.value = 1
    await tb.write(b"\x11\x22\x33")
    await Timer(30 * bit, unit="ns")
    assert sink.count() == 0 and int(dut.txd.value) == 1, "TX started with CTS deasserted"
    assert int(dut.tx_level.value) == 3

    # CTS asserted, then withdrawn in the middle of the first frame: that frame
    # completes, the next does not start.
    await FallingEdge(dut.clk)
    dut.cts_n.value = 0
    await FallingEdge(dut.txd)
    await Timer(3 * bit, unit="ns")
    # Inputs change on falling edges: a change at a rising edge would race the
    # flops in the simulator (the txd edge above is on a rising edge).
    await FallingEdge(dut.clk)
    dut.cts_n.value = 1
    await Timer(30 * bit, unit="ns")
    assert sink.read_nowait() == b"\x11" and int(dut.tx_level.value) == 2

    # Flow control off: CTS ignored.
    await FallingEdge(dut.clk)
    dut.flow_en.value = 0
    await Timer(25 * bit, unit="ns")
    assert sink.read_nowait() == b"\x22\x33"
    assert int(dut.rts_n.value) == 0


@pytest.mark.parametrize("sim", sims_for("uart"))
def test_uart(sim):
    run("uart", sim, "test_uart")
