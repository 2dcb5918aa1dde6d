# SPDX-License-Identifier: MIT
"""The quadrature-decoder reference model against its own spec: the encoder
generator's count (an oracle that knows nothing of the filter), the glitch
bounds, and the stated maximum count rate - including that it is tight."""

import math
import random

import pytest

from torqueloop.oracles.quad_decoder import (
    COUNTS_PER_MOTOR_REV,
    COUNTS_PER_SCREW_REV,
    GRAY_UP,
    QuadDecoderModel,
    QuadInputs,
    QuadSettings,
    VelocityEstimator,
    encoder_stream,
    max_count_rate,
    max_rejected_glitch_clocks,
    min_accepted_pulse_clocks,
    min_state_clocks,
    to_signed32,
)


def run_model(pins, s: QuadSettings) -> QuadDecoderModel:
    m = QuadDecoderModel()
    a, b, z = pins[0]
    for _ in range(4):
        m.clock(QuadInputs(a=a, b=b, z=z, rst=1, sample_div=s.sample_div, filter_len=s.filter_len))
    for a, b, z in pins:
        m.clock(QuadInputs(a=a, b=b, z=z, sample_div=s.sample_div, filter_len=s.filter_len))
    return m


def test_rates_of_the_default_setting_cover_the_paper_motor():
    s = QuadSettings()
    assert (s.sample_div, s.filter_len) == (49, 10)
    f_max = max_count_rate(50e6, s)
    assert f_max == pytest.approx(200e3)
    # 10k rpm at the motor shaft (upper end for a 12 V motor of this type), 64 counts/rev
    motor_rate = 10_000 / 60 * COUNTS_PER_MOTOR_REV
    assert f_max / motor_rate > 10
    assert COUNTS_PER_SCREW_REV == 8400


@pytest.mark.parametrize("sample_div,filter_len", [(0, 1), (0, 2), (0, 5), (3, 4), (1, 15), (2, 0)])
def test_model_count_equals_encoder_count_at_max_rate(sample_div, filter_len):
    seed = random.randrange(1 << 30)
    print(f"seed {seed}")
    rng = random.Random(seed)
    s = QuadSettings(sample_div, filter_len)
    for max_rate in (True, False):
        st = encoder_stream(rng, s, 400, start_phase=rng.randrange(4), max_rate=max_rate)
        m = run_model(st.pins, s)
        assert to_signed32(m.position) == st.expected_count, f"seed {seed}"
        assert m.illegal_count == st.n_illegal


@pytest.mark.parametrize("sample_div,filter_len", [(0, 2), (0, 4), (1, 6), (3, 8)])
def test_max_rate_is_tight(sample_div, filter_len):
    """One clock per state faster than min_state_clocks loses counts."""
    s = QuadSettings(sample_div, filter_len)
    h = min_state_clocks(s)
    for hold, exact in ((h, True), (h - 1, False)):
        pins = [(0, 0, 0)] * 50
        for k in range(1, 41):
            a, b = GRAY_UP[k % 4]
            pins += [(a, b, 0)] * hold
        pins += [pins[-1]] * 100
        pos = to_signed32(run_model(pins, s).position)
        assert (pos == 40) == exact, f"hold {hold}: position {pos}"


@pytest.mark.parametrize("sample_div,filter_len", [(0, 3), (2, 5), (4, 1)])
def test_glitch_bounds(sample_div, filter_len):
    s = QuadSettings(sample_div, filter_len)
    quiet = [(0, 0, 0)] * (min_accepted_pulse_clocks(s) + 10)
    for phase in range(s.sample_clocks):   # every alignment with the sample strobe
        short = quiet + [(0, 0, 0)] * phase + [(1, 0, 0)] * max_rejected_glitch_clocks(s) + quiet
        m = run_model(short, s)
        assert m.position == 0 and m.last_edge_time == 0, "short glitch counted"
        long = quiet + [(0, 0, 0)] * phase + [(1, 0, 0)] * min_accepted_pulse_clocks(s) + quiet
        m = run_model(long, s)
        assert m.position == 0 and m.last_edge_time != 0, "long pulse not seen"


def test_illegal_jump_holds_position_and_is_counted():
    s = QuadSettings(0, 2)
    pins = [(0, 0, 0)] * 20 + [(1, 1, 0)] * 20 + [(0, 0, 0)] * 20
    m = run_model(pins, s)
    assert m.position == 0 and m.illegal_count == 2 and m.illegal_flag == 1


@pytest.mark.parametrize("counts_per_s", [-10_700.0, -37.0, 5.0, 800.0, 10_700.0])
def test_velocity_from_timestamps_fast_and_slow(counts_per_s):
    """Edges of an ideal encoder at a constant rate, read every 1 ms control
    tick: the estimate is within 0.1 % once two ticks with counts have passed,
    and after a stop it decays below one count per elapsed time."""
    clk = 50e6
    tick = 50_000                                   # 1 ms in clocks
    period = clk / abs(counts_per_s)                # clocks per count
    step = 1 if counts_per_s > 0 else -1
    est = VelocityEstimator(clk_hz=clk)
    stop_at = 400 * tick

    def state(t: int) -> tuple[int, int]:
        n = int(min(t, stop_at) // period)          # counts so far
        return (n * step) & 0xFFFF_FFFF, int(n * period) & 0xFFFF_FFFF

    counted_ticks = 0
    for k in range(1, 400):
        pos, edge = state(k * tick)
        v = est.update(pos, edge, k * tick)
        if v != 0.0:
            counted_ticks += 1
        if counted_ticks >= 2:
            assert v == pytest.approx(counts_per_s, rel=1e-3), f"tick {k}"
    last_pos = None
    for k in range(400, 4000, 50):
        pos, edge = state(k * tick)
        v = est.update(pos, edge, k * tick)
        if pos == last_pos:   # no count since the last read: bounded by one count per elapsed time
            assert abs(v) <= clk / (k * tick - edge) + 1e-9
        assert math.copysign(1, v) == step
        last_pos = pos
    assert abs(v) < 1.0, "speed estimate did not decay after the stop"
