# SPDX-License-Identifier: MIT
"""Reference model of the UART (rtl/uart), written from docs/uart.md.

Three pieces, each an oracle for one part of the core:

* baud arithmetic - :func:`effective_div`, :func:`baud_of`, :func:`div_for`:
  what divisor the core uses for a ``baud_div`` setting and what rate that is;
* :class:`LineDecoder` - what an 8N1 receiver that samples each bit three
  times around its centre and votes must report for a line waveform
  (bytes, framing errors, breaks, glitches that are not start bits);
* :class:`RxFifoModel` - which received bytes reach the reader, which are
  dropped as overruns, and where RTS must stop the peer.

The line waveform is a list of (level, clocks) segments at the core's clock.
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass, field
from torqueloop.spec.system import SYSTEM

#: receiver needs at least 16 clocks per bit (three distinct sample points)
MIN_DIV = 15


@dataclass(frozen=True)
class UartParams:
    """Build-time parameters of rtl/uart/tl_uart.v."""

    clk_hz: int = SYSTEM.clk_hz
    default_baud: int = 115_200
    fifo_depth: int = 16
    rts_slack: int = 4

    @property
    def default_div(self) -> int:
        return (self.clk_hz + self.default_baud // 2) // self.default_baud - 1

    @property
    def rts_level(self) -> int:
        """RX FIFO level at and above which rts_n is high (flow control on)."""
        return self.fifo_depth - self.rts_slack


def effective_div(baud_div: int, p: UartParams = UartParams()) -> int:
    """The divisor the core runs with: 0 selects the default, 1-14 become 15."""
    if baud_div == 0:
        return p.default_div
    return max(baud_div, MIN_DIV)


def baud_of(div: int, clk_hz: int) -> float:
    """Bit rate of a divisor: one bit lasts div + 1 clocks."""
    return clk_hz / (div + 1)


def div_for(baud: float, clk_hz: int) -> int:
    """Nearest divisor for a wanted rate."""
    return max(MIN_DIV, round(clk_hz / baud) - 1)


def frame_levels(byte: int, stop: int = 1) -> list[int]:
    """Line levels of one 8N1 frame: start 0, data LSB first, stop."""
    return [0] + [(byte >> k) & 1 for k in range(8)] + [stop]


def frame_segments(byte: int, bit_clocks: float, stop: int = 1) -> list[tuple[int, float]]:
    return [(lvl, bit_clocks) for lvl in frame_levels(byte, stop)]


@dataclass
class RxEvent:
    kind: str           # "byte", "frame_error", "break"
    data: int = 0
    at_clock: float = 0.0


class LineDecoder:
    """What the receiver must report for a line waveform.

    Specification: bit k starts k * L clocks after the line falls; each bit of L clocks is sampled at L//2 - L//16, L//2 and
    L//2 + L//16 clocks into it, majority decides.  A start bit that votes 1
    is a glitch.  Stop bit 0 is a framing error, and with all data bits 0 a
    break; after either the receiver waits for the line to be high again.
    The frame ends at the stop bit's last sample.
    """

    def __init__(self, div: int) -> None:
        self.L = div + 1
        mid, q = self.L // 2, self.L // 16
        self.offsets = (mid - q, mid, mid + q)

    def decode(self, segments: list[tuple[int, float]], idle_level: int = 1) -> list[RxEvent]:
        edges = [0.0]
        for _, n in segments:
            edges.append(edges[-1] + n)
        levels = [lvl for lvl, _ in segments]

        def level_at(t: float) -> int:
            # segment containing t (segments are short lists; linear is fine)
            for k in range(len(levels)):
                if edges[k] <= t < edges[k + 1]:
                    return levels[k]
            return idle_level

        def next_time(t: float, want: int) -> float | None:
            """First time >= t with the line at ``want``."""
            if level_at(t) == want:
                return t
            for k in range(len(levels)):
                if edges[k] > t and levels[k] == want:
                    return edges[k]
            return None if want != idle_level else edges[-1]

        events: list[RxEvent] = []
        t = 0.0
        while True:
            t0 = next_time(t, 0)
            if t0 is None:
                return events
            # Sample point v reads the line v to v + 1 clocks after the start edge.
            base = t0 + 0.5
            bits = []
            for k in range(10):
                votes = [level_at(base + k * self.L + o) for o in self.offsets]
                bits.append(1 if sum(votes) >= 2 else 0)
                if k == 0 and bits[0] == 1:
                    break
            end = base + (len(bits) - 1) * self.L + self.offsets[2] + 1
            if bits[0] == 1:
                t = end
                continue
            data = sum(b << i for i, b in enumerate(bits[1:9]))
            if bits[9] == 1:
                events.append(RxEvent("byte", data, end))
                t = end
            else:
                events.append(RxEvent("frame_error", data, end))
                if data == 0:
                    events.append(RxEvent("break", 0, end))
                t_high = next_time(end, 1)
                if t_high is None:
                    return events
                t = t_high


@dataclass
class RxFifoModel:
    """RX FIFO and overrun accounting: a good byte to a full FIFO is dropped and counted."""

    p: UartParams = field(default_factory=UartParams)
    fifo: deque[int] = field(default_factory=deque)
    overruns: int = 0
    dropped: list[int] = field(default_factory=list)

    def receive(self, byte: int) -> None:
        if len(self.fifo) >= self.p.fifo_depth:
            self.overruns = min(self.overruns + 1, 0xFFFF)
            self.dropped.append(byte)
        else:
            self.fifo.append(byte)

    def read(self) -> int:
        return self.fifo.popleft()

    def rts_n(self, flow_en: bool) -> int:
        return int(flow_en and len(self.fifo) >= self.p.rts_level)
