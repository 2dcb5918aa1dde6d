# SPDX-License-Identifier: MIT
"""Count_max (eq. 4) and the frequency error of the integer divider: the
numbers docs/freq_div.md quotes and the characterisation flow relies on."""

import pytest

from torqueloop.oracles.freq_div import (FreqDivModel, FreqDivParams, carrier_hz, count_max,
                                     frequency_error, tick_hz)


def test_paper_frequencies():
    # carriers of the divisors around 50e6 / (450 * 1023) = 108.6: 452.6 / 448.4 Hz -> 109;
    # around 50e6 / (200 * 1023) = 244.4: 200.3 / 199.5 Hz -> 244
    assert count_max(450) == 109
    assert count_max(200) == 244
    assert FreqDivParams().default_div == 109


def test_20khz_lands_on_the_nearer_carrier():
    """Divisor 2 gives 24.4 kHz (+22 %), 3 gives 16.3 kHz (-19 %): the nearer is 3."""
    e = frequency_error(20_000)
    assert e.count_max == 3
    assert e.f_carrier_hz == pytest.approx(50e6 / 3 / 1023)
    assert e.error_carrier == pytest.approx(-0.1854, abs=1e-4)
    assert abs(carrier_hz(3) - 20_000) < abs(carrier_hz(2) - 20_000)


def test_sweep_50_to_500_hz_error_below_half_percent():
    """Over the paper's sweep (section VI.A) the carrier lands within half a divisor step."""
    for f in range(50, 501, 10):
        e = frequency_error(f)
        assert abs(e.error_carrier) <= 0.5 / e.count_max * 1.01 + 1e-12, (f, e)
        assert abs(e.error_carrier) < 0.005, (f, e)
        for d in (e.count_max - 1, e.count_max + 1):   # no neighbour is nearer
            assert abs(e.f_carrier_hz - f) <= abs(carrier_hz(d) - f)
        # the pins' carrier is 1024/1023 of eq. 2's
        assert e.f_carrier_hz == pytest.approx(e.f_eq2_hz * 1024 / 1023)


def test_zero_and_one_tick_every_clock():
    assert tick_hz(0) == tick_hz(1) == 50e6
    assert carrier_hz(2) == pytest.approx(50e6 / 2 / 1023)


def test_clipping_to_register():
    assert count_max(1, div_bits=8) == 255
    assert count_max(10e6) == 1
    with pytest.raises(ValueError):
        count_max(0)


def test_model_tick_spacing():
    model = FreqDivModel(FreqDivParams(div_bits=8))
    model.clock(div_we=1, div_in=5)
    ticks = [model.clock()[0] for _ in range(50)]
    idx = [k for k, t in enumerate(ticks) if t]
    assert all(b - a == 5 for a, b in zip(idx, idx[1:]))
