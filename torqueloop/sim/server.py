# SPDX-License-Identifier: MIT
"""A simulated board's UART on a local TCP port, like the RN-XV's bridge.

One client at a time (the RN-XV takes one); the board keeps running between
connections.  Simulated time follows the wall clock times ``speed`` (so the
firmware's link watchdog and the host's timeouts mean what they mean on the
real board); if the plant cannot keep up, the board runs as fast as it can
and answers bytes between control iterations all the same, and the time it
lost is given up, not caught up later: a burst of simulated time faster
than the wall clock would let the firmware's link watchdog or the boot
ROM's 500 ms window expire between two messages of a host that keeps to
the real-time rules.  ``hello``
sends ``*HELLO*`` on connect, as an RN-XV does before ``set comm remote 0``.

Any :class:`~torqueloop.sim.simboard.BytePipe` can be served, so the RTL
co-simulation can be put on the same port as the firmware-in-the-loop board.
"""

from __future__ import annotations

import select
import socket
import sys
import time
from typing import Callable

from .simboard import BytePipe

MAX_STEP_S = 0.005   # simulated time between two looks at the socket
MAX_LAG_S = 0.02     # a board further behind the wall clock slips instead of catching up


class BoardServer:
    def __init__(self, board: BytePipe, host: str = "127.0.0.1", port: int = 2000, *,
                 speed: float = 1.0, hello: bool = False,
                 log: Callable[[str], None] | None = None) -> None:
        self.board, self.speed, self.hello = board, speed, hello
        self.log = log or (lambda s: print(s, file=sys.stderr, flush=True))
        self.sock = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
        self.sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        self.sock.bind((host, port))
        self.sock.listen(1)
        self.sock.setblocking(False)
        self.port = self.sock.getsockname()[1]
        self.client: socket.socket | None = None
        self._stop = False
        self._t0, self._sim0 = time.monotonic(), board.t

    def stop(self) -> None:
        self._stop = True

    def _accept(self) -> None:
        try:
            c, addr = self.sock.accept()
        except BlockingIOError:
            return
        if self.client is not None:
            self._read_client(64)    # a client that has just hung up is gone, not busy
        if self.client is not None:
            c.close()          # the RN-XV refuses a second client; so do we
            return
        c.setblocking(False)
        c.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        self.client = c
        self.log(f"client {addr[0]}:{addr[1]} connected")
        if self.hello:
            self._send(b"*HELLO*")

    def _read_client(self, chunks: int = 1) -> None:
        """Up to ``chunks`` reads of what the client sent, to the board; drops
        the client at the end of its stream."""
        for _ in range(chunks):
            if self.client is None:
                return
            try:
                data = self.client.recv(4096)
            except BlockingIOError:
                return
            except OSError:
                data = b""
            if not data:
                self._drop()
                return
            self.board.write(data)

    def _send(self, data: bytes) -> None:
        if self.client is None or not data:
            return
        try:
            self.client.sendall(data)
        except OSError:
            self._drop()

    def _drop(self) -> None:
        if self.client is not None:
            self.client.close()
            self.client = None
            self.log("client disconnected")

    def serve_forever(self, until: Callable[[], bool] | None = None) -> None:
        self._t0, self._sim0 = time.monotonic(), self.board.t
        try:
            while not self._stop and not (until and until()):
                self.turn()
        finally:
            self._drop()
            self.sock.close()

    def turn(self) -> None:
        """One look at the sockets and at most MAX_STEP_S of simulated time."""
        socks = [self.sock] + ([self.client] if self.client else [])
        ahead = (self.board.t - self._sim0) - (time.monotonic() - self._t0) * self.speed
        wait = max(0.0, min(MAX_STEP_S, ahead / self.speed)) if self.speed > 0 else 0.0
        readable, _, _ = select.select(socks, [], [], wait)
        if self.client is not None and self.client in readable:
            self._read_client()
        if self.sock in readable:
            self._accept()
        self._send(self.board.read())
        behind = (time.monotonic() - self._t0) * self.speed - (self.board.t - self._sim0)
        if self.speed > 0 and behind > MAX_LAG_S:
            self._t0 += (behind - MAX_LAG_S) / self.speed     # slip: never run faster than real time
            behind = MAX_LAG_S
        if self.speed <= 0 or behind > 0:
            self.board.advance(MAX_STEP_S if self.speed <= 0 else min(MAX_STEP_S, behind + 1e-6))
            self._send(self.board.read())
