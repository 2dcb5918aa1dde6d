# SPDX-License-Identifier: MIT
"""The cocotb harness of the co-simulation: the same board image
(torqueloop/sim/harness/rtl_loop_top.v), plant bridge (torqueloop.sim.pins), host link
and experiment runner (torqueloop.sim.experiment) as the native harness,
with the board behind cocotb instead of a C++ main.

The experiment runner is blocking code; it runs in a cocotb bridge thread
and every board access is a `resume`d coroutine, so the simulator and the
runner never run at once.  Python wakes only at bridge pin edges, at the
encoder edges and UART bits it scheduled, and at the end of a run; the
clock is cocotb's Clock (GPI implementation, no Python per edge).

Timing is cycle-exact with the native harness: cycle n is the n-th rising
edge (at 20 n - 10 ns); inputs for cycle n are applied 5 ns before the
edge n + 1; the UART line is sampled right after the edges the native
deserialiser samples at.  The same run therefore gives the same telemetry
on both harnesses, which the benchmark checks (scripts/benches/bench_rtl_loop.py).

Run by :func:`torqueloop.sim.cocotb_run.run` (environment: TL_COSIM_CFG
JSON of ExperimentConfig, TL_COSIM_OUT pickle path of the RtlRun).
"""

from __future__ import annotations

import json
import os
import pickle

import cocotb
from cocotb.clock import Clock
from cocotb.simtime import get_sim_time
from cocotb.task import bridge, resume
from cocotb.triggers import FallingEdge, First, Timer, ValueChange

from torqueloop.sim import experiment

PS_PER_CYCLE = 20_000


def _t_apply(cycle: int) -> int:
    """ps at which an input for cycle index ``cycle`` is set (5 ns before edge cycle+1)."""
    return cycle * PS_PER_CYCLE + 5_000


def _t_after(cycle: int) -> int:
    """ps just after rising edge ``cycle`` (edge k at 20 k - 10 ns)."""
    return cycle * PS_PER_CYCLE - 10_000 + 1_000


class CocotbBoard:
    def __init__(self, dut) -> None:
        self.dut = dut
        self._cycle = 0
        self.div = 434
        self._edges: list[tuple[int, int, int, int, int]] = []
        self._edge_task = None
        self._enc = [0, 0, 0]
        self._txq: list[int] = []
        self._tx_task = None
        self._rx: list[tuple[int, int]] = []
        self._rx_errors = 0
        self._pin_sigs = (dut.rpwm, dut.lpwm, dut.r_en, dut.l_en)
        for s, v in ((dut.reset_n, 0), (dut.key0_n, 1), (dut.sw0, 0), (dut.fault_n, 3), (dut.lim_neg, 0), (dut.lim_pos, 0), (dut.host_tx, 1),
                     (dut.enc_a, 0), (dut.enc_b, 0), (dut.enc_z, 0)):
            s.value = v
        cocotb.start_soon(self._rx_loop())

    # ---- helpers in simulator context --------------------------------------
    def _now_ps(self) -> int:
        return int(get_sim_time("ps"))

    async def _until(self, t_ps: int) -> None:
        now = self._now_ps()
        if t_ps > now:
            await Timer(t_ps - now, unit="ps")

    @staticmethod
    def _bit(sig) -> int:
        v = sig.value
        return int(v) & 1 if v.is_resolvable else 1      # an undriven line reads as idle

    def _pins_now(self) -> int:
        p = 0
        for k, s in enumerate(self._pin_sigs):
            raw = s.value
            v = int(raw) if raw.is_resolvable else 0      # X before reset on four-state simulators
            for ax in (0, 1):
                p |= ((v >> ax) & 1) << (4 * ax + k)
        return p

    async def _edge_loop(self) -> None:
        while self._edges:
            c, ax, a, b, z = self._edges[0]
            await self._until(_t_apply(c))
            self._edges.pop(0)
            m = 1 << ax
            for i, v in enumerate((a, b, z)):
                self._enc[i] = (self._enc[i] & ~m) | (v << ax)
            self.dut.enc_a.value = self._enc[0]
            self.dut.enc_b.value = self._enc[1]
            self.dut.enc_z.value = self._enc[2]
        self._edge_task = None

    async def _tx_loop(self) -> None:
        c = self._cycle
        while self._txq:
            byte = self._txq.pop(0)
            bits = [0] + [(byte >> i) & 1 for i in range(8)] + [1]
            for bit in bits:
                await self._until(_t_apply(c))
                self.dut.host_tx.value = bit
                c += self.div
        self._tx_task = None

    async def _rx_loop(self) -> None:
        while True:
            await FallingEdge(self.dut.host_rx)
            if not self.dut.host_rx.value.is_resolvable:
                continue
            n = (self._now_ps() + 10_000) // PS_PER_CYCLE
            m = n + self.div + self.div // 2
            byte = 0
            for i in range(8):
                await self._until(_t_after(m + i * self.div))
                byte |= self._bit(self.dut.host_rx) << i
            await self._until(_t_after(m + 8 * self.div))
            if self._bit(self.dut.host_rx):
                self._rx.append((byte, n))
            else:
                self._rx_errors += 1

    # ---- BoardPort -------------------------------------------------------------
    @property
    def cycle(self) -> int:
        return self._cycle

    @resume
    async def pins(self) -> int:
        return self._pins_now()

    @resume
    async def set_board(self, reset_n: int, key0_n: int, sw0: int, fault_n: int = 3) -> None:
        self.dut.reset_n.value = reset_n
        self.dut.key0_n.value = key0_n
        self.dut.sw0.value = sw0
        self.dut.fault_n.value = fault_n

    def set_uart_div(self, clocks_per_bit: int) -> None:
        self.div = clocks_per_bit

    @resume
    async def push_edges(self, cycles, axis, a, b, z) -> None:
        self._edges += [(int(c), int(x), int(p), int(q), int(r)) for c, x, p, q, r in zip(cycles, axis, a, b, z)]
        if self._edges and self._edge_task is None:
            self._edge_task = cocotb.start_soon(self._edge_loop())

    @resume
    async def clear_edges(self) -> None:
        self._edges.clear()

    @resume
    async def run(self, until_cycle: int, stop_on_pins: bool = True) -> bool:
        before = self._pins_now()
        while self._cycle < until_cycle:
            timer = Timer(_t_after(until_cycle) - self._now_ps(), unit="ps")
            if stop_on_pins:
                await First(timer, *(ValueChange(s) for s in self._pin_sigs))
            else:
                await timer
            self._cycle = min(until_cycle, (self._now_ps() + 10_000) // PS_PER_CYCLE)
            if stop_on_pins and self._pins_now() != before and self._cycle < until_cycle:
                return True
        return stop_on_pins and self._pins_now() != before

    @resume
    async def uart_send(self, data: bytes) -> None:
        self._txq += list(data)
        if self._tx_task is None:
            self._tx_task = cocotb.start_soon(self._tx_loop())

    def uart_recv(self) -> tuple[bytes, list[int]]:
        rx, self._rx = self._rx, []
        return bytes(b for b, _ in rx), [c for _, c in rx]

    def uart_errors(self) -> int:
        return self._rx_errors


@cocotb.test()
async def rtl_loop_run(dut) -> None:
    """One experiment run (configuration from TL_COSIM_CFG), result pickled to TL_COSIM_OUT."""
    kw = json.loads(os.environ["TL_COSIM_CFG"])
    kw = {k: tuple(v) if isinstance(v, list) else v for k, v in kw.items()}   # JSON has no tuples
    cfg = experiment.ExperimentConfig(**kw)
    Clock(dut.clk, 20, unit="ns").start(start_high=False)
    board = CocotbBoard(dut)
    run = await bridge(experiment.run_rtl)(cfg, lambda rom, ram: board)
    with open(os.environ["TL_COSIM_OUT"], "wb") as f:
        pickle.dump(run, f)
