# SPDX-License-Identifier: MIT
"""The trapezoid profile's promises (docs/firmware.md, "Control" and "Fourth pass"),
checked as properties of the reference model torqueloop/oracles/servo.py over random
moves - not by equality with an oracle, since the oracle is the definition (the C
follows it bit for bit: tests/test_firmware_host.py):

* the speed never exceeds VMAX T and changes by at most AMAX T^2 per sample,
  including the first sample and the stop on the target;
* it lands exactly on the target, and a move it can stop for never passes it;
* a new target mid-move (ahead, behind, closer than the stopping distance) is
  reached the same way: a reversal brakes first, at most AMAX T^2 per sample;
* a new VMAX or AMAX mid-move: the speed keeps the new limits from then on,
  except above a lowered VMAX, where it drops to it at once (the velocity limit
  wins) or, when it cannot stop from there, brakes toward it by AMAX T^2."""

from __future__ import annotations

import random

import pytest

from torqueloop.oracles.servo import Axis, AxisParams, stop_sum

#: fixed seeds, and one fresh per run (the ``seed`` fixture, printed; TORQUELOOP_SEED=<n> reruns it)
SEEDS = [1, 2, 3, None]


def _axis(rng: random.Random) -> Axis:
    p = AxisParams(vmax_cps=rng.choice([rng.randrange(1, 300), rng.randrange(1, 300_000)]),
                   amax_cps2=rng.choice([rng.randrange(1, 3000), rng.randrange(1, 10**7)]))
    return Axis(p, rng.choice([50, 200, 1000, rng.randrange(50, 25_001)]))


def _far(ax: Axis, rng: random.Random) -> int:
    """A random target within +-20 000 counts that the profile reaches in under 20 000 samples."""
    reach = min(20_000, (ax.vmax_q16 * 10_000 >> 16) + 1)
    return rng.randrange(-reach, reach)


def _run(ax: Axis, limit: int = 400_000) -> list[int]:
    """Set-points (q16) until the profile rests."""
    sp = [ax.sp_q16]
    while ax.moving and len(sp) < limit:
        ax.step(0, 0, 0, run=False)
        sp.append(ax.sp_q16)
    return sp


def _speeds(sp: list[int]) -> list[int]:
    return [b - a for a, b in zip(sp, sp[1:])] + [0]


def _within_limits(sp: list[int], v0: int, vmax: int, amax: int) -> str | None:
    v_prev = v0
    for k, v in enumerate(_speeds(sp)):
        if abs(v) > vmax:
            return f"sample {k}: speed {v} beyond vmax {vmax}"
        if abs(v - v_prev) > amax:
            return f"sample {k}: speed {v_prev} -> {v}, more than amax {amax}"
        v_prev = v
    return None


@pytest.mark.parametrize("fixed", SEEDS)
def test_moves_from_rest_keep_the_limits_and_land_without_passing(fixed: int | None, seed: int) -> None:
    seed = seed if fixed is None else fixed
    print(f"seed {seed}")
    rng = random.Random(seed)
    for n in range(150):
        ax = _axis(rng)
        start = rng.randrange(-10**6, 10**6)
        dist = rng.choice([0, 1, -1, rng.randrange(-50, 50), rng.randrange(-20_000, 20_000)])
        if ax.vmax_q16 * 20_000 < abs(dist) << 16:       # keep the run short
            dist = dist % 7
        ax.reset(start, 0)
        ax.move(start + dist, True)
        sp = _run(ax)
        what = f"seed {seed}, move {n}: {dist} counts, vmax {ax.vmax_q16} amax {ax.amax_q16} q16"
        assert not ax.moving and sp[-1] == (start + dist) << 16, what
        assert all(min(start, start + dist) << 16 <= x <= max(start, start + dist) << 16 for x in sp), what
        assert (err := _within_limits(sp, 0, ax.vmax_q16, ax.amax_q16)) is None, f"{what}: {err}"


@pytest.mark.parametrize("fixed", SEEDS)
def test_a_new_target_mid_move_keeps_the_limits_and_lands(fixed: int | None, seed: int) -> None:
    """Retargets at random samples of a move, including ones too close to stop for and ones
    behind the axis: the speed changes by at most AMAX T^2 every sample from start to
    rest (the reversal brakes first), and the last target is reached exactly."""
    print(f"seed {seed}")
    rng = random.Random(seed)
    overruns = 0
    for n in range(150):
        ax = _axis(rng)
        ax.reset(0, 0)
        ax.move(_far(ax, rng), True)
        sp = [ax.sp_q16]
        for _ in range(rng.randrange(1, 4)):
            for _ in range(rng.randrange(1, 400)):
                ax.step(0, 0, 0, run=False)
                sp.append(ax.sp_q16)
                if not ax.moving:
                    break
            if not ax.moving:   # landed: a move from rest is the test above's
                break
            v = ax.prof_v_q16
            if v and rng.random() < 0.5:      # a target closer than the stopping distance, ahead
                tgt = (ax.sp_q16 + (1 if v > 0 else -1) * rng.randrange(stop_sum(abs(v), ax.amax_q16) + 1)) >> 16
                overruns += 1
            else:
                tgt = _far(ax, rng)
            ax.move(tgt, True)
        sp += _run(ax)[1:]
        what = f"seed {seed}, run {n}: vmax {ax.vmax_q16} amax {ax.amax_q16} q16"
        assert not ax.moving and sp[-1] == ax.target_q16, what
        assert (err := _within_limits(sp, 0, ax.vmax_q16, ax.amax_q16)) is None, f"{what}: {err}"
    assert overruns > 25


@pytest.mark.parametrize("fixed", SEEDS)
def test_a_new_vmax_or_amax_mid_move_is_obeyed_from_then_on(fixed: int | None, seed: int) -> None:
    seed = seed if fixed is None else fixed
    print(f"seed {seed}")
    rng = random.Random(seed)
    for n in range(100):
        ax = _axis(rng)
        ax.reset(0, 0)
        tgt = _far(ax, rng)
        ax.move(tgt, True)
        for _ in range(rng.randrange(1, 300)):
            ax.step(0, 0, 0, run=False)
        if not ax.moving:
            continue
        ax.p.vmax_cps = max(1, ax.p.vmax_cps * rng.choice([1, 2]) // rng.choice([1, 2, 3]))
        ax.p.amax_cps2 = max(1, ax.p.amax_cps2 * rng.choice([1, 2]) // rng.choice([1, 2, 3]))
        ax.derive()
        v_prev = ax.prof_v_q16
        sp = _run(ax)
        what = f"seed {seed}, run {n}: vmax {ax.vmax_q16} amax {ax.amax_q16} q16, speed {v_prev}"
        assert not ax.moving and sp[-1] == tgt << 16, what
        for k, v in enumerate(_speeds(sp)):
            if abs(v_prev) > ax.vmax_q16:    # above a lowered VMAX: down to it at once, or braking by AMAX
                assert abs(v) <= ax.vmax_q16 or (v * v_prev > 0 and abs(v) == abs(v_prev) - ax.amax_q16), \
                    f"{what}, sample {k}: {v_prev} -> {v}"
            else:
                assert abs(v) <= ax.vmax_q16 and abs(v - v_prev) <= ax.amax_q16, f"{what}, sample {k}: {v_prev} -> {v}"
            v_prev = v
