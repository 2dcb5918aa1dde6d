"""Count_max (eq. 4) and the frequency error of the integer divider: the
numbers docs/freq_div.md quotes and the characterisation flow relies on."""

import pytest

from torqueloop.models.freq_div import (FreqDivModel, FreqDivParams, carrier_hz, count_max,
                                     frequency_error, tick_hz)


def test_paper_frequencies():
    # 50e6 / (450 * 1024) = 108.5 -> 109; 50e6 / (200 * 1024) = 244.1 -> 244
    assert count_max(450) == 109
    assert count_max(200) == 244
    assert FreqDivParams().default_div == 109


def test_20khz_is_22_percent_high():
    e = frequency_error(20_000)
    assert e.count_max == 2
    assert e.f_eq2_hz == pytest.approx(24_414.0625)
    assert e.error_eq2 == pytest.approx(0.2207, abs=1e-4)


def test_sweep_50_to_500_hz_error_below_half_percent():
    """Over the paper's sweep (section VI.A) the rounding error stays small."""
    for f in range(50, 501, 10):
        e = frequency_error(f)
        assert abs(e.error_eq2) <= 0.5 / e.count_max + 1e-12
        assert abs(e.error_eq2) < 0.005, (f, e)
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
