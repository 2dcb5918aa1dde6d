# SPDX-License-Identifier: MIT
"""A client of ``torqueloop serve`` with the public methods of
:class:`~torqueloop.host.client.Client`, so the CLI's commands run the
same through a server as over their own link (torqueloop/host/serve.py has
the wire protocol).  The server holds the key: this side needs none."""

from __future__ import annotations

import collections
import json
import socket
import time
from typing import Any

from torqueloop.spec import protocol as P

from . import client as C
from .serve import PROTOCOL, VERSION, split_addr

#: error kinds the server sends back, as the client's own exceptions
_KINDS: dict[str, type[C.ProtocolError]] = {
    k.__name__: k for k in (C.NoAnswer, C.LinkClosed, C.ReplyLost, C.KeyMissing, C.AuthFailed,
                            C.BoardHasNoKey, C.ProtocolError)}


class ServerError(C.ProtocolError):
    """The server refused a request it did not understand."""


def _raise(err: dict) -> None:
    kind, msg = err.get("kind", ""), err.get("message", "")
    if kind == "CommandRejected":
        e = C.CommandRejected.__new__(C.CommandRejected)
        Exception.__init__(e, msg)
        e.command, e.status = err.get("command", ""), err.get("status", -1)
        e.why = err.get("why", P.REFUSAL["NONE"])
        raise e
    if kind in _KINDS:
        raise _KINDS[kind](msg)
    if kind in ("ValueError", "BadValue"):
        raise ValueError(msg)
    raise ServerError(f"the torqueloop server says: {msg}")


class RemoteClient:
    """``torqueloop serve`` at ``addr`` (``HOST:PORT``)."""

    key = None                    # the server holds the key

    def __init__(self, addr: str, timeout: float = 5.0) -> None:
        self.addr = addr
        host, port = split_addr(addr)
        try:
            self.sock = socket.create_connection((host, port), timeout=timeout)
        except OSError as e:
            raise C.LinkClosed(f"cannot reach the torqueloop server at {addr} ({e}); is `torqueloop serve` "
                               "running? (--no-server talks to the board directly)") from None
        self.timeout = timeout
        self._buf = b""
        self._id = 0
        self.telemetry_queue: collections.deque[dict] = collections.deque(maxlen=100_000)
        hello = self._line(time.monotonic() + timeout)
        if hello is None or hello.get("protocol") != PROTOCOL:
            raise C.ProtocolError(f"{addr} is not a torqueloop server (it said {hello!r})")
        if hello.get("version") != VERSION:
            raise C.ProtocolError(f"the torqueloop server at {addr} speaks version {hello.get('version')}, "
                                  f"this tool {VERSION}: use the same torqueloop for both")
        self.board_url = hello.get("board", "")
        self.key_id = hello.get("key_id")
        self.identity: dict[str, int] | None = hello.get("identity")

    # ---- lines -----------------------------------------------------------------------
    def _line(self, deadline: float) -> dict | None:
        """The next JSON line before ``deadline`` (None: none yet)."""
        while b"\n" not in self._buf:
            left = deadline - time.monotonic()
            if left <= 0:
                return None
            self.sock.settimeout(left)
            try:
                data = self.sock.recv(65536)
            except socket.timeout:
                return None
            except OSError as e:
                raise C.LinkClosed(f"the torqueloop server at {self.addr} dropped the connection ({e})") from None
            if not data:
                raise C.LinkClosed(f"the torqueloop server at {self.addr} closed the connection")
            self._buf += data
        line, self._buf = self._buf.split(b"\n", 1)
        return json.loads(line)

    def _call(self, method: str, **params: Any) -> Any:
        self._id += 1
        rid = self._id
        try:
            self.sock.sendall((json.dumps({"id": rid, "method": method, "params": params}) + "\n").encode())
        except OSError as e:
            raise C.LinkClosed(f"the torqueloop server at {self.addr} dropped the connection ({e})") from None
        # a command waits its turn behind the other clients' commands: allow for the queue
        deadline = time.monotonic() + max(30.0, self.timeout)
        while True:
            msg = self._line(deadline)
            if msg is None:
                raise C.NoAnswer(f"no answer to {method} from the torqueloop server at {self.addr}")
            if msg.get("type") == "telemetry":
                self.telemetry_queue.append(msg["record"])
            elif msg.get("id") == rid:
                if "error" in msg:
                    _raise(msg["error"])
                return msg.get("result")

    # ---- Client's public methods ---------------------------------------------------------
    def connect(self) -> dict[str, int]:
        self.identity = self._call("identify")
        return self.identity

    identify = connect

    def get_param(self, name: str, axis: int = 0) -> int:
        return self._call("get_param", name=name, axis=axis)

    def set_param(self, name: str, value: int, axis: int = 0) -> int:
        return self._call("set_param", name=name, value=value, axis=axis)

    def enable(self, mask: int, on: bool = True) -> None:
        self._call("enable", mask=mask, on=on)

    def move(self, axis: int, target_counts: int, trapezoid: bool = False, unhomed: bool = False) -> None:
        self._call("move", axis=axis, target=target_counts, trapezoid=trapezoid, unhomed=unhomed)

    def drive(self, axis: int, duty: int) -> None:
        self._call("drive", axis=axis, duty=duty)

    def home(self, axis: int, mode: str, index: bool = False) -> None:
        self._call("home", axis=axis, mode=mode, index=index)

    def heartbeat(self) -> None:
        self._call("heartbeat")

    def stop(self, mask: int) -> None:
        self._call("stop", mask=mask)

    def status(self, axis: int = 0) -> dict[str, int]:
        return self._call("status", axis=axis)

    def clear_fault(self, mask: int) -> tuple[int, int]:
        f0, f1 = self._call("clear_fault", mask=mask)
        return f0, f1

    def counters(self) -> dict[str, int]:
        return self._call("counters")

    def store_report(self) -> dict[str, int] | None:
        return self._call("store_report")

    def save(self) -> dict[str, int]:
        return self._call("save")

    def holds(self) -> dict[str, list[str]]:
        return self._call("holds")

    @property
    def stats(self) -> C.LinkStats:
        """The server's link counters (its one session with the board)."""
        return C.LinkStats(**self._call("stats"))

    def set_telemetry(self, every: int) -> None:
        if every:
            self._call("subscribe", every=every)
        else:
            self._call("unsubscribe")

    def pump(self, duration: float) -> None:
        end = time.monotonic() + duration
        while True:
            msg = self._line(end)
            if msg is None:
                return
            if msg.get("type") == "telemetry":
                self.telemetry_queue.append(msg["record"])

    def take_telemetry(self) -> list[dict]:
        out = list(self.telemetry_queue)
        self.telemetry_queue.clear()
        return out

    def close(self) -> None:
        try:
            self.sock.close()
        except OSError:
            pass
