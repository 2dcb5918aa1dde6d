# SPDX-License-Identifier: MIT
"""Unit tests of the co-simulation pieces that do not need the RTL
(torqueloop.sim): plant snapshot/rollback, the speculative plant-on-pins
scheme against a direct plant run, the eq. (26)-(27) RMSE."""

from __future__ import annotations

import math
import random

import numpy as np
import pytest

from sim_models.bridge import Pins
from sim_models.stepper import TwoAxisPlant
from torqueloop.sim import pins as cp
from torqueloop.spec.metrics import rmse, step_metrics


def _pins_code(p0: Pins, p1: Pins) -> int:
    code = 0
    for ax, p in enumerate((p0, p1)):
        code |= (p.rpwm | p.lpwm << 1 | p.r_en << 2 | p.l_en << 3) << (4 * ax)
    return code


class FakeBoard:
    """A PWM source with known pin-change cycles instead of the RTL: axis 0
    forward at duty d0 with period P0, axis 1 reverse at d1 / P1; the duties
    change at ``switch_cycle``.  Records the encoder edges it is given."""

    def __init__(self, seed: int) -> None:
        rng = random.Random(seed)
        self.p = (rng.randrange(20_000, 60_000), rng.randrange(30_000, 90_000))
        self.d = [(rng.random(), rng.random()), (rng.random(), rng.random())]
        self.switch_cycle = rng.randrange(200_000, 600_000)
        self.c = 0
        self.edges: list[tuple[int, int, int, int, int]] = []
        self.queue: list[tuple[int, int, int, int, int]] = []

    def pins_at(self, c: int) -> tuple[Pins, Pins]:
        k = 0 if c < self.switch_cycle else 1
        out = []
        for ax in (0, 1):
            on = (c % self.p[ax]) < int(self.d[k][ax] * self.p[ax])
            out.append(Pins(int(on and ax == 0), int(on and ax == 1), 1, 1))
        return out[0], out[1]

    @property
    def cycle(self) -> int:
        return self.c

    def pins(self) -> int:
        return _pins_code(*self.pins_at(self.c))

    def push_edges(self, cycles, axis, a, b, z) -> None:
        self.queue += [(int(c), int(x), int(p), int(q), int(r)) for c, x, p, q, r in zip(cycles, axis, a, b, z)]

    def clear_edges(self) -> None:
        self.queue.clear()

    def next_change(self, c: int) -> int:
        """First cycle after c at which the pins may differ."""
        k = 0 if c < self.switch_cycle else 1
        cands = [self.switch_cycle] if c < self.switch_cycle else []
        for ax in (0, 1):
            per, on = self.p[ax], int(self.d[k][ax] * self.p[ax])
            base = c - c % per
            cands += [x for x in (base + on, base + per, base + per + on) if x > c]
        return min(cands)

    def run(self, until: int, stop_on_pins: bool = True) -> bool:
        before = self.pins()
        while self.c < until:
            n = min(until, self.next_change(self.c))
            while self.queue and self.queue[0][0] < n:
                self.edges.append(self.queue.pop(0))
            self.c = n
            if stop_on_pins and self.pins() != before:
                return True
        return False


def test_snapshot_restore_is_exact() -> None:
    from sim_models.variants import load_variant

    p = load_variant("lab")     # every mode: rotor stick-slip, brush drop, mesh sign
    a, b = TwoAxisPlant(p, seed=0, energy=True, glitch_rate_hz=200.0), \
        TwoAxisPlant(p, seed=0, energy=True, glitch_rate_hz=200.0)
    fwd = (Pins(1, 0, 1, 1), Pins(0, 1, 1, 1))
    for pl in (a, b):
        pl.advance(0.02, fwd)
    snap = b.snapshot()
    b.advance(0.013, (Pins(0, 0, 1, 1), Pins(0, 0, 0, 0)))
    b.restore(snap)
    ea = a.advance(0.004, fwd)
    eb = b.advance(0.004, fwd)
    assert ea == eb
    for ax in (0, 1):
        assert np.array_equal(a.state(ax), b.state(ax))
        assert a.count(ax) == b.count(ax)
        assert a.charge(ax) == b.charge(ax) and a.current_sq_integral(ax) == b.current_sq_integral(ax)


def test_plant_on_pins_matches_direct_run(seed: int) -> None:
    """The speculative steps with rollback give the plant state and the encoder
    edges (at the clock they fall on) of a plant advanced directly from pin
    change to pin change."""
    end = 1_000_000                        # 20 ms
    board = FakeBoard(seed)
    bridge = cp.PlantOnPins(TwoAxisPlant(seed=0), board, horizon_cycles=7_919)
    # start the motors turning so edges occur: 20 ms forward/reverse first, both ways the same
    warm = (Pins(1, 0, 1, 1), Pins(0, 1, 1, 1))
    bridge.plant.advance(0.1, warm)
    direct = TwoAxisPlant(seed=0)
    direct.advance(0.1, warm)
    for stop in (30_000, 61_234, 500_001, end):
        bridge.run_to(stop)
    while board.queue and board.queue[0][0] < end:
        board.edges.append(board.queue.pop(0))
    ref_edges = []
    c = 0
    while c < end:
        p = board.pins_at(c)
        n = c
        while True:
            n = min(end, board.next_change(n))
            if n >= end or board.pins_at(n) != p:
                break
        for e in direct.advance((n - c) * cp.TICK_S, p):
            ref_edges.append((c + math.ceil(e.t * cp.CLK_HZ - 1e-6), e.axis, e.a, e.b, e.z))
        c = n
    assert bridge.stats.rollbacks > 0 and bridge.stats.edges > 20
    # same edges, same order; the clock may differ by a few: the plant places an
    # edge by cubic Hermite interpolation inside its step, so a different split of
    # the same interval moves edge times by tens of ns (measured up to 3 clocks)
    assert [e[1:] for e in board.edges] == [e[1:] for e in ref_edges]
    shift = np.array([e[0] for e in board.edges]) - np.array([e[0] for e in ref_edges])
    assert np.abs(shift).max() <= 5, shift
    print(f"{len(shift)} edges, clock shift {np.abs(shift).max()} max, {np.count_nonzero(shift)} moved")
    for ax in (0, 1):
        np.testing.assert_allclose(bridge.plant.state(ax), direct.state(ax), rtol=1e-6, atol=1e-9)


def test_rmse_eq26_27() -> None:
    t = np.linspace(0, 40, 1601)
    e = np.stack([np.full_like(t, 0.03), np.full_like(t, 0.04)], axis=1)
    assert rmse(t, e) == pytest.approx(0.05)                 # sqrt(e_x^2 + e_z^2)
    assert rmse(t, np.sin(2 * np.pi * t)) == pytest.approx(math.sqrt(0.5), rel=1e-3)


def test_step_metrics() -> None:
    t = np.linspace(0, 10, 401)
    x = 1 - np.exp(-t) * np.cos(3 * t)
    m = step_metrics(t, x, 1.0)
    assert 0 < m.overshoot_pct < 40
    # last exit from the band: inside the envelope bound exp(-t) = 0.02, after exp(-t) = 0.04
    assert -math.log(0.04) < m.settling_time_s <= -math.log(0.02)
    assert np.all(np.abs(x[t >= m.settling_time_s] - 1) <= 0.02)
    assert step_metrics(t, t / 20, 1.0).settling_time_s is None
