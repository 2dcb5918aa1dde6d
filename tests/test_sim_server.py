# SPDX-License-Identifier: MIT
"""The simulated board's TCP bridge (torqueloop.sim.server): one client at a
time, and a client that has just hung up does not make the next one "busy"."""

from __future__ import annotations

import socket
import time

from torqueloop.sim.server import BoardServer


class EchoPipe:
    """A BytePipe that records what it is sent and echoes it back."""

    def __init__(self) -> None:
        self.t = 0.0
        self.got = b""
        self._out = b""

    def write(self, data: bytes) -> None:
        self.got += data
        self._out += data

    def read(self) -> bytes:
        out, self._out = self._out, b""
        return out

    def advance(self, max_dt: float) -> float:
        self.t += max_dt
        return max_dt


def make() -> tuple[BoardServer, EchoPipe]:
    pipe = EchoPipe()
    return BoardServer(pipe, port=0, speed=0, log=lambda s: None), pipe


def connect(server: BoardServer) -> socket.socket:
    c = socket.create_connection(("127.0.0.1", server.port))
    time.sleep(0.05)                                 # the SYN and any data wait in the server's queues
    return c


def test_second_client_is_refused_while_the_first_holds_the_board() -> None:
    server, pipe = make()
    first = connect(server)
    server.turn()
    assert server.client is not None
    second = connect(server)
    server.turn()
    second.settimeout(1.0)
    assert second.recv(16) == b""                    # closed at once, like the RN-XV
    first.sendall(b"ab")
    time.sleep(0.05)
    server.turn()
    first.settimeout(1.0)
    assert first.recv(16) == b"ab" and pipe.got == b"ab"
    first.close()
    second.close()
    server.sock.close()


def test_a_client_that_just_hung_up_is_not_busy() -> None:
    # the race CI met: the old client's last bytes and its end of stream, and
    # the next client's connection, all waiting in one turn of the loop
    server, pipe = make()
    old = connect(server)
    server.turn()
    old.sendall(b"xy")
    old.close()
    new = connect(server)
    server.turn()
    assert pipe.got == b"xy"                         # the old client's last bytes still reached the board
    assert server.client is not None and server.client.getpeername() == new.getsockname()
    new.sendall(b"z")
    time.sleep(0.05)
    server.turn()
    new.settimeout(1.0)
    assert new.recv(16) == b"xyz"                    # the board answers whoever holds the link, as an RN-XV does
    new.close()
    server.client.close()
    server.sock.close()
