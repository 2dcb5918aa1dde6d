# SPDX-License-Identifier: MIT
"""The UART reference model against the 8N1 spec: baud arithmetic, the
three-sample line decoder with rate mismatch, framing errors, breaks and
glitches, and the RX FIFO's overrun and RTS accounting."""

import random

import pytest

from torqueloop.oracles.uart import (
    LineDecoder,
    RxFifoModel,
    UartParams,
    baud_of,
    div_for,
    effective_div,
    frame_segments,
)


def test_reset_default_is_115200_at_50mhz():
    p = UartParams()
    assert effective_div(0, p) == 433
    assert baud_of(433, p.clk_hz) == pytest.approx(115200, rel=1e-4)
    assert effective_div(3, p) == 15 and effective_div(200, p) == 200
    # RN-XV rates: error of the nearest divisor at 50 MHz stays below 0.5 % up to 921600
    for baud in (9600, 19200, 38400, 57600, 115200, 230400, 460800, 921600):
        err = baud_of(div_for(baud, p.clk_hz), p.clk_hz) / baud - 1
        assert abs(err) < 5e-3, (baud, err)


@pytest.mark.parametrize("div", [15, 31, 433])
@pytest.mark.parametrize("mismatch", [-0.03, 0.0, 0.03])
def test_decoder_reads_bytes_with_rate_mismatch(div, mismatch):
    seed = random.randrange(1 << 30)
    print(f"seed {seed}")
    rng = random.Random(seed)
    data = bytes(rng.getrandbits(8) for _ in range(20))
    segs = [(1, 5)]
    for b in data:
        segs += frame_segments(b, (div + 1) * (1 + mismatch))
    ev = LineDecoder(div).decode(segs)
    assert [e.kind for e in ev] == ["byte"] * len(data), f"seed {seed}"
    assert bytes(e.data for e in ev) == data


def test_decoder_fails_beyond_its_tolerance():
    """A sender 8 % fast must not decode cleanly (so the tolerance test above means something)."""
    data = bytes(range(0x55, 0x55 + 10))
    segs = [(1, 5)]
    for b in data:
        segs += frame_segments(b, 64 * 0.92)
    ev = LineDecoder(63).decode(segs)
    assert bytes(e.data for e in ev if e.kind == "byte") != data


def test_framing_error_break_and_glitch():
    L = 32
    segs = [(1, L)] + frame_segments(0x81, L, stop=0) + [(1, L)]
    segs += [(0, 5), (1, 2 * L)]                    # too short to be a start bit
    segs += [(0, 30 * L), (1, 2 * L)]               # break
    segs += frame_segments(0x00, L) + [(1, L)]      # a zero byte is not a break
    ev = LineDecoder(L - 1).decode(segs)
    assert [(e.kind, e.data) for e in ev] == [
        ("frame_error", 0x81), ("frame_error", 0), ("break", 0), ("byte", 0)]


def test_rx_fifo_overrun_and_rts():
    p = UartParams(fifo_depth=8, rts_slack=3)
    m = RxFifoModel(p)
    for k in range(11):
        m.receive(k)
        assert m.rts_n(True) == (len(m.fifo) >= 5)
        assert m.rts_n(False) == 0
    assert m.overruns == 3 and m.dropped == [8, 9, 10]
    assert [m.read() for _ in range(8)] == list(range(8))
