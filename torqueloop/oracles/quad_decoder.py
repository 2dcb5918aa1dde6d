# SPDX-License-Identifier: MIT
"""Reference model of the quadrature decoder (rtl/motion/tl_quad_decoder.v).

Written from the specification in docs/quad_decoder.md, not from the RTL:

* a clock-level model, :class:`QuadDecoderModel`, that the cocotb test runs in
  lock-step with the core and compares every output against every clock;
* an encoder waveform generator, :func:`encoder_stream`, that yields pin
  levels per clock together with the count a correct decoder must end on
  (an independent, end-to-end oracle that knows nothing of the filter's
  internals);
* the rate limits of the filter, :func:`max_count_rate`, which the docs
  table and the benchmark print.

Default encoder (board README, inferred from G = 131.25 in the paper):
64 counts per motor revolution, 8400 counts per ball-screw revolution.
"""

from __future__ import annotations

import math
import random
from dataclasses import dataclass, field

from torqueloop.spec.system import SYSTEM

#: counts per motor-shaft revolution (16 lines, 4x decoding)
COUNTS_PER_MOTOR_REV = SYSTEM.counts_per_motor_rev
#: gearbox ratio G of the paper
GEAR_RATIO = SYSTEM.gear_ratio
#: counts per output (ball-screw) revolution
COUNTS_PER_SCREW_REV = SYSTEM.counts_per_turn  # 8400


@dataclass(frozen=True)
class QuadSettings:
    """Run-time settings of one decoder; the defaults are the reset values the
    register block should use (f_s = 1 MHz at 50 MHz, N = 10 samples)."""

    sample_div: int = 49   # sample every sample_div + 1 clocks
    filter_len: int = 10   # N samples a level must persist (0 acts as 1)

    @property
    def n(self) -> int:
        return max(self.filter_len, 1)

    @property
    def sample_clocks(self) -> int:
        return self.sample_div + 1


def max_count_rate(clk_hz: float, s: QuadSettings) -> float:
    """Highest count rate (counts/s) decoded without loss for ideal quadrature
    (90 degree phase, 50 % duty) in one direction.

    Each state must span a sample (T >= T_s) so that the A and B edges land on
    different samples, and each channel level - two states long - must span N
    samples (2 T >= N T_s).  Hence f_max = f_s * min(1, 2 / N).
    """
    fs = clk_hz / s.sample_clocks
    return fs * min(1.0, 2.0 / s.n)


def min_state_clocks(s: QuadSettings) -> int:
    """Shortest whole-clock state duration that is still decoded exactly."""
    return max(s.sample_clocks, math.ceil(s.n * s.sample_clocks / 2))


def max_rejected_glitch_clocks(s: QuadSettings) -> int:
    """Longest pulse (in clocks) that is always rejected: it covers at most N - 1 samples."""
    return (s.n - 1) * s.sample_clocks


def min_accepted_pulse_clocks(s: QuadSettings) -> int:
    """Shortest pulse (in clocks) that is always accepted: it covers at least N samples."""
    return s.n * s.sample_clocks


def _u32(x: int) -> int:
    return x & 0xFFFF_FFFF


def to_signed32(x: int) -> int:
    x = _u32(x)
    return x - (1 << 32) if x & 0x8000_0000 else x


@dataclass
class QuadInputs:
    """Everything the core samples at one rising clock edge."""

    a: int = 0
    b: int = 0
    z: int = 0
    rst: int = 0
    sample_div: int = 0
    filter_len: int = 1
    pos_load: int = 0
    pos_load_val: int = 0
    illegal_clear: int = 0
    index_arm: int = 0


@dataclass
class QuadDecoderModel:
    """Clock-level model: call :meth:`clock` once per rising edge."""

    ts_bits: int = 32
    illegal_bits: int = 16
    # pin synchroniser (two flops, not reset)
    meta: int | None = None
    stable: int | None = None
    div_cnt: int = 0
    filt: int = 0                     # filtered {z, b, a}
    filt_cnt: list[int] = field(default_factory=lambda: [0, 0, 0])
    prev: int = 0
    position: int = 0                 # unsigned 32-bit
    dir: int = 0
    illegal_count: int = 0
    illegal_flag: int = 0
    index_pos: int = 0
    index_seen: int = 0
    index_armed: int = 0
    timestamp: int = 0
    last_edge_time: int = 0
    edge_interval: int = 0

    def clock(self, i: QuadInputs) -> None:
        pins = (i.z << 2) | (i.b << 1) | i.a
        sync = self.stable
        # The synchronisers are free-running; everything else uses their output.
        self.stable, self.meta = self.meta, pins
        if i.rst:
            self.div_cnt = 0
            # unknown until the synchroniser has filled: why rst lasts >= 3 clocks
            self.filt = self.prev = sync if sync is not None else 0
            self.filt_cnt = [0, 0, 0]
            self.position = self.dir = 0
            self.illegal_count = self.illegal_flag = 0
            self.index_pos = self.index_seen = self.index_armed = 0
            self.timestamp = self.last_edge_time = self.edge_interval = 0
            return
        assert sync is not None
        ts_mask = (1 << self.ts_bits) - 1
        ill_max = (1 << self.illegal_bits) - 1

        # Decode the change made by the previous sample (registers as they are now).
        da = (self.filt ^ self.prev) & 1
        db = ((self.filt ^ self.prev) >> 1) & 1
        step = da ^ db
        illegal = da & db
        up = ((self.prev >> 1) ^ self.filt) & 1
        z_rise = (self.filt >> 2) & 1 and not (self.prev >> 2) & 1

        if step:
            self.dir = up
            self.edge_interval = (self.timestamp - self.last_edge_time) & ts_mask
            self.last_edge_time = self.timestamp
        old_position = self.position
        if i.pos_load:
            self.position = _u32(i.pos_load_val)
        elif step:
            self.position = _u32(self.position + (1 if up else -1))

        if illegal:
            self.illegal_flag = 1
            self.illegal_count = 1 if i.illegal_clear else min(self.illegal_count + 1, ill_max)
        elif i.illegal_clear:
            self.illegal_count = self.illegal_flag = 0

        if i.index_arm:
            self.index_seen, self.index_armed = 0, 1
        elif self.index_armed and z_rise:
            self.index_pos, self.index_seen, self.index_armed = old_position, 1, 0

        self.prev = self.filt
        self.timestamp = (self.timestamp + 1) & ts_mask

        # Sample strobe and N-sample filter.
        if self.div_cnt == 0:
            n = max(i.filter_len, 1)
            for ch in range(3):
                s = (sync >> ch) & 1
                if s == (self.filt >> ch) & 1:
                    self.filt_cnt[ch] = 0
                elif self.filt_cnt[ch] + 1 >= n:
                    self.filt = (self.filt & ~(1 << ch)) | (s << ch)
                    self.filt_cnt[ch] = 0
                else:
                    self.filt_cnt[ch] += 1
            self.div_cnt = i.sample_div
        else:
            self.div_cnt -= 1

    def outputs(self) -> dict[str, int]:
        """The core's output ports, as unsigned integers."""
        return {
            "position": self.position, "dir": self.dir,
            "illegal_count": self.illegal_count, "illegal_flag": self.illegal_flag,
            "index_pos": self.index_pos, "index_seen": self.index_seen,
            "index_armed": self.index_armed, "timestamp": self.timestamp,
            "last_edge_time": self.last_edge_time, "edge_interval": self.edge_interval,
            "enc_filtered": self.filt,
        }


# --- encoder waveforms ---------------------------------------------------------------------

#: Gray sequence of (A, B) for counting up: A leads B.
GRAY_UP = [(0, 0), (1, 0), (1, 1), (0, 1)]


@dataclass
class EncoderStream:
    """Per-clock pin levels and the count a correct decoder ends on."""

    pins: list[tuple[int, int, int]]  # (a, b, z) per clock
    expected_count: int               # net legal steps (illegal jumps count 0)
    n_steps: int = 0
    n_glitches_short: int = 0
    n_glitches_long: int = 0
    n_illegal: int = 0
    n_index: int = 0


def encoder_stream(rng: random.Random, s: QuadSettings, n_events: int, start_phase: int = 0,
                   p_glitch: float = 0.15, p_illegal: float = 0.03, p_index: float = 0.02,
                   max_rate: bool = False) -> EncoderStream:
    """A random encoder waveform at up to the filter's maximum count rate.

    Steps hold each state for ``min_state_clocks`` to 4x that (exactly the
    minimum when ``max_rate``); reversals and the states around glitches,
    illegal jumps and index pulses dwell long enough (N samples) that the
    net count is defined by the spec alone: glitches of at most
    ``max_rejected_glitch_clocks`` are ignored, longer single-channel pulses
    count one step and back (net 0), an illegal jump (both channels at once)
    counts 0.
    """
    h_min = min_state_clocks(s)
    settle = min_accepted_pulse_clocks(s) + 2 * s.sample_clocks + 4
    phase = start_phase % 4
    out = EncoderStream(pins=[], expected_count=0)
    last_dir = 1

    def emit(a: int, b: int, z: int, n: int) -> None:
        out.pins.extend([(a, b, z)] * n)

    a, b = GRAY_UP[phase]
    emit(a, b, 0, settle)
    for _ in range(n_events):
        r = rng.random()
        a, b = GRAY_UP[phase]
        if r < p_glitch + p_illegal + p_index:
            emit(a, b, 0, settle)  # keep the event clear of the last step
        if r < p_glitch:
            # A pulse on one channel from a stable state; short ones must vanish.
            short = rng.random() < 0.6
            if short:
                width = rng.randint(1, max(1, max_rejected_glitch_clocks(s)))
                out.n_glitches_short += 1
            else:
                width = rng.randint(min_accepted_pulse_clocks(s), min_accepted_pulse_clocks(s) + 3 * s.sample_clocks)
                out.n_glitches_long += 1
            if rng.random() < 0.5:
                emit(a ^ 1, b, 0, width)
            else:
                emit(a, b ^ 1, 0, width)
            emit(a, b, 0, settle)
        elif r < p_glitch + p_illegal:
            phase = (phase + 2) % 4
            a, b = GRAY_UP[phase]
            emit(a, b, 0, settle)
            out.n_illegal += 1
        elif r < p_glitch + p_illegal + p_index:
            emit(a, b, 1, settle)
            emit(a, b, 0, settle)
            out.n_index += 1
        else:
            d = last_dir if rng.random() < 0.9 else -last_dir
            if d != last_dir:
                # A reversal makes a one-state pulse: it must last N samples
                # (a real shaft dwells there while it stops).
                emit(a, b, 0, settle)
            phase = (phase + d) % 4
            a, b = GRAY_UP[phase]
            emit(a, b, 0, h_min if max_rate else rng.randint(h_min, 4 * h_min))
            out.expected_count += d
            out.n_steps += 1
            last_dir = d
    emit(*GRAY_UP[phase], 0, settle)
    return out


# --- speed from counts over time (what firmware does with the timestamps) ---------------------

@dataclass
class VelocityEstimator:
    """Counts-over-time speed estimate from the decoder's registers, as
    LinuxCNC's hostmot2 encoder does; the reference for the firmware's
    fixed-point version.

    Call :meth:`update` once per control tick with ``position``,
    ``last_edge_time`` and ``timestamp`` read in that tick.  With new counts,
    the speed is the counts divided by the time between the last counted
    edges of the previous and this tick (not the tick period), which is
    exact to one clock however slow the shaft.  Without new counts, the
    shaft cannot be faster than one count since the last edge, so the
    estimate decays as CLK_HZ / (timestamp - last_edge_time).
    """

    clk_hz: float
    ts_bits: int = 32
    velocity: float = 0.0            # counts/s
    _pos: int | None = None
    _edge: int = 0

    def update(self, position: int, last_edge_time: int, timestamp: int) -> float:
        mask = (1 << self.ts_bits) - 1
        if self._pos is None:
            self._pos, self._edge = position, last_edge_time
            return self.velocity
        dpos = to_signed32(position - self._pos)
        if dpos != 0:
            dt = (last_edge_time - self._edge) & mask
            if dt > 0:
                self.velocity = dpos * self.clk_hz / dt
            self._pos, self._edge = position, last_edge_time
        else:
            since = (timestamp - self._edge) & mask
            if since > 0:
                bound = self.clk_hz / since
                if abs(self.velocity) > bound:
                    self.velocity = math.copysign(bound, self.velocity)
        return self.velocity
