# SPDX-License-Identifier: MIT
"""The co-simulation's transport: the host tool's own protocol client
(torqueloop.host.client.Client) talks to a simulated board's UART through
it, and its blocking read runs the board and the plant on while the client
waits for bytes, as a real line would pass time.  Time is the board's clock:
:meth:`SimTransport.seconds` is the client's clock, so its answer timeouts are
simulated time, and each 0x00-delimited chunk is stamped with the clock of
its first byte's start bit (``chunk_times``), which the client puts on each
telemetry record (``rx_time``)."""

from __future__ import annotations

import collections
from dataclasses import dataclass
from typing import Callable

from torqueloop.host.client import Client
from torqueloop.spec import auth
from torqueloop.spec.system import SYSTEM

#: clocks the board runs on per blocking read that finds nothing (the client's poll step)
READ_STEP_CYCLES = 20_000
#: the client's answer timeout in simulated seconds (5 000 000 clocks)
ANSWER_TIMEOUT_S = 0.1


@dataclass
class Telemetry:
    cycle: int                 # clock of the start bit of the frame's first byte after its 0x00
    time_us: int               # firmware time of the control sample (ticks x period)
    axes: list[dict]           # per axis: setpoint, position, velocity_q8, error, pwm_cmd, faults, enabled


def telemetry(client: Client) -> list[Telemetry]:
    """The telemetry records the client queued over a :class:`SimTransport`, with their clocks."""
    return [Telemetry(f["rx_time"], f["time_us"], f["axes"]) for f in client.telemetry_queue]


class SimTransport:
    """``send(bytes)`` puts bytes on the line to the FPGA, ``recv()`` returns
    what arrived and the clock of each byte's start bit, ``advance(cycles)``
    runs board and plant that much further, ``now()`` is the clock count."""

    def __init__(self, send: Callable[[bytes], None], recv: Callable[[], tuple[bytes, list[int]]],
                 advance: Callable[[int], None], now: Callable[[], int], clk_hz: int = SYSTEM.clk_hz) -> None:
        self.send, self.recv, self.advance, self.now, self.clk_hz = send, recv, advance, now, clk_hz
        self._rx = bytearray()
        self.chunk_times: collections.deque[int] = collections.deque()
        self._in_chunk = False

    def seconds(self) -> float:
        return self.now() / self.clk_hz

    def _pull(self) -> None:
        data, cycles = self.recv()
        for byte, cyc in zip(data, cycles):
            if byte and not self._in_chunk:
                self.chunk_times.append(cyc)
                self._in_chunk = True
            elif not byte:
                self._in_chunk = False
        self._rx += data

    @property
    def in_waiting(self) -> int:
        self._pull()
        return len(self._rx)

    def write(self, data: bytes) -> int:
        self.send(data)
        return len(data)

    def read(self, size: int = 1) -> bytes:
        """Up to ``size`` bytes; with none waiting, the board runs READ_STEP_CYCLES on first."""
        self._pull()
        if not self._rx:
            self.advance(READ_STEP_CYCLES)
            self._pull()
        out = bytes(self._rx[:size])
        del self._rx[:size]
        return out

    def close(self) -> None:
        pass


def sim_client(transport: SimTransport, key: bytes | None = auth.TEST_KEY) -> Client:
    """The host client on a simulated board: no retries (the simulated line
    loses nothing, so a retry would only hide a fault), answer timeout in
    simulated time."""
    return Client(transport, timeout=ANSWER_TIMEOUT_S, retries=0, clock=transport.seconds, key=key,
                  key_source="the public test key")
