# SPDX-License-Identifier: MIT
"""What the protocol client talks through: a :class:`Transport`, and the
board's transports by URL, through pyserial's ``serial_for_url``.

``/dev/ttyUSB0`` (or ``COM3``) opens a serial port at ``baud``;
``socket://host:2000`` opens a TCP connection (the RN-XV's bridge, or the
simulated board of ``torqueloop sim``); ``loop://`` is pyserial's loopback.
The co-simulation's transport (torqueloop.sim.link) runs the simulated board
while the client waits, and tests script fake ones.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol

DEFAULT_BAUD = 115200   # the firmware's BAUD_DIV default (docs/protocol.md)


class Transport(Protocol):
    """A byte pipe whose read blocks for at most a short poll interval (what
    :class:`serial.Serial` offers).  Optional, read with ``getattr``:
    ``in_waiting`` (bytes that a read returns at once) and ``chunk_times``
    (a deque with the arrival time of each 0x00-delimited chunk read so far,
    in order; the client stamps each telemetry record with it)."""

    def write(self, data: bytes) -> int | None: ...

    def read(self, size: int = 1) -> bytes: ...

    def close(self) -> None: ...


@dataclass(frozen=True)
class LinkInfo:
    url: str
    kind: str          # "serial", "tcp" or "other"
    baud: int


def classify(url: str) -> str:
    if url.startswith("socket://"):
        return "tcp"
    if "://" in url:
        return "other"
    return "serial"


class LinkOpenError(OSError):
    """The link could not be opened; the message says what to check."""


def open_link(url: str, baud: int = DEFAULT_BAUD, timeout: float = 0.05) -> tuple[Transport, LinkInfo]:
    """Open ``url``; ``timeout`` is the read poll interval, not the answer timeout."""
    import serial  # pyserial; imported here so --help works without it

    kind = classify(url)
    try:
        port = serial.serial_for_url(url, baudrate=baud, timeout=timeout, write_timeout=2.0)
    except (serial.SerialException, OSError, ValueError) as e:
        hint = {
            "serial": "check the port name (ls /dev/ttyUSB* /dev/ttyACM*), that no other program "
                      "holds it, and that you are in the 'dialout' group",
            "tcp": "check the address and port (the RN-XV listens on 2000, `torqueloop sim` on 2000 "
                   "unless told otherwise), that the module joined the network and that "
                   "no other client is connected (the RN-XV takes one at a time)",
        }.get(kind, "check the URL")
        raise LinkOpenError(f"cannot open {url}: {e}; {hint}") from None
    return port, LinkInfo(url, kind, baud)
