# SPDX-License-Identifier: MIT
"""The plant on the board's pins: the loop closes only through them.

The board (any :class:`BoardPort`: the native Verilator harness or the cocotb
one) runs with its bridge pins held; the plant (sim_models.TwoAxisPlant) is
advanced over the same stretch with those pins and its encoder edges are
scheduled on the board's encoder pins at the clock they fall on.  Nothing
inside the RTL is read.

Causality without a per-clock handshake: the plant is advanced
*speculatively* over a horizon with the pins present now, its edges are
queued, and the board runs until the horizon or until a bridge pin changes.
If a pin changed first, the plant is rolled back to the state saved at the
start and advanced again only up to the change (the flow is deterministic,
so the edges up to there are the ones already applied).  The horizon ends at
the predicted next pin change (a PWM waveform repeats with its period:
c[n+1] = c[n-1] + (c[n] - c[n-2])), so a rollback happens only when the
firmware changes the duty; the error of the scheme is the rounding of edge
times up to the next 20 ns clock, as for a real input pin.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from typing import Protocol

import numpy as np

from sim_models.bridge import Pins
from sim_models.stepper import TwoAxisPlant
from torqueloop.spec.system import SYSTEM

CLK_HZ = SYSTEM.clk_hz
TICK_S = 1.0 / CLK_HZ


class BoardPort(Protocol):
    """What the bridge needs of a simulated board: its clock count, the
    bridge pin levels (bit 4*axis + 0..3 = RPWM, LPWM, R_EN, L_EN), an
    encoder edge queue and a run that stops on a bridge pin change."""

    @property
    def cycle(self) -> int: ...
    def pins(self) -> int: ...
    def push_edges(self, cycles: np.ndarray, axis: np.ndarray, a: np.ndarray, b: np.ndarray,
                   z: np.ndarray) -> None: ...
    def clear_edges(self) -> None: ...
    def run(self, until_cycle: int, stop_on_pins: bool = True) -> bool: ...


def decode_pins(code: int) -> tuple[Pins, Pins]:
    return tuple(Pins((code >> (4 * a)) & 1, (code >> (4 * a + 1)) & 1,   # type: ignore[return-value]
                      (code >> (4 * a + 2)) & 1, (code >> (4 * a + 3)) & 1) for a in (0, 1))


@dataclass
class BridgeStats:
    segments: int = 0           # plant advances that stood (pins constant over them)
    rollbacks: int = 0          # speculative advances undone by an early pin change
    edges: int = 0              # encoder edges delivered
    pin_changes: int = 0
    board_s: float = 0.0        # wall time inside the board's run (the RTL)
    plant_s: float = 0.0        # wall time advancing the plant (incl. snapshots and rollbacks)


@dataclass
class PlantOnPins:
    """Co-simulates ``plant`` with ``board``; call :meth:`run_to` repeatedly."""

    plant: TwoAxisPlant
    board: BoardPort
    horizon_cycles: int = 50_000            # 1 ms: longest speculative step
    stats: BridgeStats = field(default_factory=BridgeStats)
    _changes: list[list[int]] = field(default_factory=lambda: [[], []])
    #: injected encoder faults per axis: None, "frozen" (no edge reaches the pins
    #: any more) or "reversed" (A and B swapped: the count runs the wrong way)
    encoder_fault: list = field(default_factory=lambda: [None, None])
    _last_code: int = -1
    #: after :meth:`watch`: the clocks of each axis's first pin changes (up to 16)
    watched: list[list[int]] = field(default_factory=lambda: [[], []])
    _watch_from: int | None = None

    def watch(self, from_cycle: int) -> None:
        """Record the pin changes of each axis from ``from_cycle`` on, in :attr:`watched`."""
        self._watch_from = from_cycle
        self.watched = [[], []]

    def _predict(self, now: int) -> int | None:
        best = None
        for ch in self._changes:
            if len(ch) >= 3:
                nxt = ch[-2] + (ch[-1] - ch[-3])
                while nxt <= now:            # prediction already passed: next period
                    nxt += max(1, ch[-1] - ch[-3])
                best = nxt if best is None else min(best, nxt)
        return best

    def _note(self, code: int, cycle: int) -> None:
        if self._last_code >= 0 and code != self._last_code:
            self.stats.pin_changes += 1
            for ax in (0, 1):
                if (code >> (4 * ax)) & 0xF != (self._last_code >> (4 * ax)) & 0xF:
                    ch = self._changes[ax]
                    ch.append(cycle)
                    if self._watch_from is not None and cycle >= self._watch_from and len(self.watched[ax]) < 16:
                        self.watched[ax].append(cycle)
                    if len(ch) > 4:
                        del ch[0]
        self._last_code = code

    def _push(self, edges: list, c0: int, first_cycle: int) -> None:
        if not edges:
            return
        t = np.fromiter((e.t for e in edges), float, len(edges))
        cyc = c0 + np.ceil(t * CLK_HZ - 1e-6).astype(np.int64)
        keep = cyc >= first_cycle
        if not keep.any():
            return
        fault = self.encoder_fault
        keep &= np.fromiter((fault[e.axis] != "frozen" for e in edges), bool, len(edges))
        if not keep.any():
            return
        sel = [e for e, k in zip(edges, keep) if k]
        swap = [fault[e.axis] == "reversed" for e in sel]
        self.board.push_edges(cyc[keep].astype(np.uint64), np.array([e.axis for e in sel]),
                              np.array([e.b if s else e.a for e, s in zip(sel, swap)]),
                              np.array([e.a if s else e.b for e, s in zip(sel, swap)]),
                              np.array([e.z for e in sel]))
        self.stats.edges += len(sel)

    def run_to(self, until_cycle: int) -> None:
        """Advance board and plant together to ``until_cycle`` (clock count)."""
        b = self.board
        while True:
            c0 = b.cycle
            if c0 >= until_cycle:
                return
            code = b.pins()
            self._note(code, c0)
            pins = decode_pins(code)
            end = min(until_cycle, c0 + self.horizon_cycles)
            pred = self._predict(c0)
            if pred is not None and c0 < pred < end:
                end = pred
            t0 = time.perf_counter()
            snap = self.plant.snapshot()
            edges = self.plant.advance((end - c0) * TICK_S, pins)
            self._push(edges, c0, c0)
            t1 = time.perf_counter()
            stopped = b.run(end, True)
            c1 = b.cycle
            t2 = time.perf_counter()
            self.stats.segments += 1
            if stopped and c1 < end:
                # a pin changed before the horizon: redo the plant up to the change
                self.stats.rollbacks += 1
                b.clear_edges()
                self.plant.restore(snap)
                edges = self.plant.advance((c1 - c0) * TICK_S, pins)
                self._push(edges, c0, c1)
            self.stats.board_s += t2 - t1
            self.stats.plant_s += t1 - t0 + time.perf_counter() - t2


def counts_per_rad(plant: TwoAxisPlant) -> float:
    p = plant.params
    return p.encoder.counts_per_motor_rev * p.axes[0].gear_ratio / (2 * math.pi)
