# SPDX-License-Identifier: MIT
"""The pwm_torque reference mapping (eq. 1 with eq. 19/25 saturation) against
its definition in docs/pwm_torque.md, and the divide-by-(2^N - 1) identity
the RTL relies on, exhaustively."""

import random

import numpy as np
import pytest

from torqueloop.oracles.pwm_torque import (PwmInputs, PwmTorqueModel, full_scale, map_direction,
                                       map_duty)


@pytest.mark.parametrize("n", [4, 6, 8, 10, 12])
def test_rtl_division_identity_is_exact(n):
    """floor(x / M) == (x + (x >> N) + 1) >> N for every x the RTL can form
    (x = mag * span + (M - 1) / 2), so the hardware's shift-and-add divider is
    the reference's exact round-half-up division."""
    m = full_scale(n)
    x = np.arange(m * m + (m - 1) // 2 + 1, dtype=np.int64)
    assert np.array_equal((x + (x >> n) + 1) >> n, x // m)


@pytest.mark.parametrize("n", [6, 10])
def test_ends_zero_and_dead_zone(n):
    m = full_scale(n)
    for pw0, pw_max in [(0, m), (m // 5, m - m // 10), (m // 2, m // 2), (0, 0), (m, m)]:
        span = pw_max - pw0
        assert map_duty(0, pw0, pw_max, n) == 0
        for sign in (1, -1):
            one = map_duty(sign, pw0, pw_max, n)
            assert one == pw0 + (1 if 2 * span >= m else 0), (pw0, pw_max, one)
            assert map_duty(sign * m, pw0, pw_max, n) == pw_max
            # -2^N (the one code beyond -M) saturates to -M
            assert map_duty(-(m + 1), pw0, pw_max, n) == pw_max


@pytest.mark.parametrize("n", [6, 10])
def test_monotonic_linear_and_within_limit(n):
    m = full_scale(n)
    rng = random.Random(1234)
    for _ in range(200):
        pw0, pw_max = rng.randint(0, m), rng.randint(0, m)
        duties = [map_duty(c, pw0, pw_max, n) for c in range(1, m + 1)]
        assert all(b >= a for a, b in zip(duties, duties[1:])), "not monotonic"
        assert max(duties) <= pw_max, "above the limit"
        if pw_max >= pw0:
            ideal = [pw0 + c * (pw_max - pw0) / m for c in range(1, m + 1)]
            assert max(abs(d - i) for d, i in zip(duties, ideal)) <= 0.5, "more than half a count off the line"
            assert min(duties) >= pw0, "inside the dead zone"
        else:
            assert set(duties) == {pw_max}, "pw_max below PW0 must clamp every command to pw_max"
        # symmetric in the sign of the command
        assert all(map_duty(-c, pw0, pw_max, n) == map_duty(c, pw0, pw_max, n) for c in range(1, m + 1, 7))


def test_direction():
    assert map_direction(5) == 0 and map_direction(-5) == 1 and map_direction(0) == 0


def test_model_period_is_m_ticks_and_duty_counts_high():
    """The clock model on its own: M ticks per period, duty ticks high, latched at the start."""
    n, m = 6, full_scale(6)
    model = PwmTorqueModel(n)
    inp = PwmInputs(tick=1, cmd=20, pw0=0, pw_max=m, enable=1)
    outs = [model.clock(inp) for _ in range(5 * m)]
    starts = [k for k, o in enumerate(outs) if o.period_start]
    assert all(b - a == m for a, b in zip(starts, starts[1:]))
    last = outs[starts[-2]:starts[-1]]
    assert sum(o.rpwm for o in last) == 20 and not any(o.lpwm for o in last)
