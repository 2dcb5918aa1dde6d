# SPDX-License-Identifier: MIT
"""Quadrature encoder on the motor shaft: angle -> A/B/Z states and edges.

Default resolution 64 counts per motor revolution (16 lines, both edges of
both channels; board README), so 64 x 131.25 = 8400 counts per screw turn.
The count is ``floor(phi / rad_per_count + phase_offset_counts)``; the offset
of half a count puts the rest position mid-state, so a motor at rest does not
sit on an edge.  The A/B state is the Gray code of ``count mod 4``
((0,0) (1,0) (1,1) (0,1) for counting up); Z is high while
``count mod index_every_counts == 0``.
"""

from __future__ import annotations

import math
import random
from typing import NamedTuple

import numpy as np

from sim_models.params import EncoderParams

_GRAY = ((0, 0), (1, 0), (1, 1), (0, 1))


class Edge(NamedTuple):
    """Pin state (a, b, z) of ``axis`` from time ``t`` on (seconds)."""

    t: float
    axis: int
    a: int
    b: int
    z: int


def count_of(phi_rad: float, p: EncoderParams) -> int:
    return math.floor(phi_rad / p.rad_per_count + p.phase_offset_counts)


def pins_of(count: int, p: EncoderParams) -> tuple[int, int, int]:
    a, b = _GRAY[count & 3]
    return a, b, 1 if count % p.index_every_counts == 0 else 0


def edges_from_samples(t: np.ndarray, phi: np.ndarray, axis: int, p: EncoderParams,
                       out: list[Edge]) -> int:
    """Append one Edge per count change along the sampled angle path
    (linear between samples, so every intermediate count is visited in
    order and no state is skipped).  Returns the count at the last sample."""
    u = phi / p.rad_per_count + p.phase_offset_counts
    cnt = np.floor(u).astype(np.int64)
    steps = np.nonzero(np.diff(cnt))[0]
    for k in steps:
        c0, c1 = int(cnt[k]), int(cnt[k + 1])
        u0, u1 = u[k], u[k + 1]
        step = 1 if c1 > c0 else -1
        c = c0
        while c != c1:
            nxt = c + step
            thr = nxt if step > 0 else c   # crossing value of u
            frac = (thr - u0) / (u1 - u0)
            tt = float(t[k] + frac * (t[k + 1] - t[k]))
            out.append(Edge(tt, axis, *pins_of(nxt, p)))
            c = nxt
    return int(cnt[-1])


def hermite(phi0: float, w0: float, phi1: float, w1: float, tau: float,
            s: np.ndarray) -> np.ndarray:
    """Cubic Hermite interpolation of the angle over one step (s in [0, 1])."""
    s2 = s * s
    s3 = s2 * s
    return ((2 * s3 - 3 * s2 + 1) * phi0 + (s3 - 2 * s2 + s) * tau * w0
            + (-2 * s3 + 3 * s2) * phi1 + (s3 - s2) * tau * w1)


def add_glitches(edges: list[Edge], t0: float, t1: float, rate_hz: float, width_s: float,
                 state: dict[int, tuple[int, int, int]], rng: random.Random) -> list[Edge]:
    """Insert noise glitches into the edge list of the interval [t0, t1):
    at Poisson-distributed times one channel (A or B, chosen at random) flips
    for ``width_s`` and flips back, as a pickup spike on the cable would.
    ``state`` holds each axis's pin state at t0 and is updated.  A glitch is
    never reported across a real edge (it is dropped if one falls inside),
    nor across another glitch (one starting before the last one ended is
    dropped: two overlapping flips of A and B would reach the pins as both
    channels changing at once, which no single pickup spike does)."""
    if rate_hz <= 0:
        for e in edges:
            state[e.axis] = (e.a, e.b, e.z)
        return edges
    out: list[Edge] = []
    by_axis: dict[int, list[Edge]] = {}
    for e in edges:
        by_axis.setdefault(e.axis, []).append(e)
    for axis in state:
        real = by_axis.get(axis, [])
        t = t0
        glitches = []
        while True:
            t += rng.expovariate(rate_hz)
            if t >= t1 - width_s:
                break
            glitches.append((t, rng.randrange(2)))
        cur = state[axis]
        ri = 0
        busy_until = -math.inf
        for tg, ch in glitches:
            while ri < len(real) and real[ri].t <= tg:
                cur = real[ri][2:]
                out.append(real[ri])
                ri += 1
            if tg < busy_until or (ri < len(real) and real[ri].t < tg + width_s):
                continue
            busy_until = tg + width_s
            a, b, z = cur
            g = (1 - a, b, z) if ch == 0 else (a, 1 - b, z)
            out.append(Edge(tg, axis, *g))
            out.append(Edge(tg + width_s, axis, *cur))
        for e in real[ri:]:
            cur = e[2:]
            out.append(e)
        state[axis] = cur
    out.sort(key=lambda e: e.t)
    return out
