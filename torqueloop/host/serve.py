# SPDX-License-Identifier: MIT
"""``torqueloop serve``: one process owns the board's link and its
authenticated session; any number of local clients watch and command
through it (the way Klipper's Moonraker or ODrive's GUI backend do).

The board (RN-XV, USB-UART or the simulated board) takes one client, and
every ``torqueloop`` process used to open its own link and session; so
``monitor`` in one terminal made ``move`` in another "busy".  The server
keeps the one :class:`~torqueloop.host.client.Client` and serialises every
command of every client on it (one at a time, in arrival order); the link
key stays in this process.

Wire protocol (docs/host.md, "The session server"): TCP, by default on
127.0.0.1 only, one JSON object per line (UTF-8, ``\\n``) each way:

- on connect the server sends ``{"type": "hello", "protocol":
  "torqueloop-serve", "version": 1, "board": URL, "identity": {...},
  "key_id": ID or null}``;
- a request is ``{"id": ANY, "method": NAME, "params": {...}}``; the answer
  carries the same ``id`` and either ``"result"`` or ``"error": {"kind":
  CLASS, "message": TEXT, "command": ..., "status": ..., "why": ...}``;
- ``subscribe`` ``{"every": N}`` starts ``{"type": "telemetry", "record":
  {...}}`` lines (one record every N control periods) until
  ``unsubscribe`` or the end of the connection.

Methods (params in brackets): ``identify``, ``status`` [axis],
``get_param`` [name, axis], ``set_param`` [name, value, axis], ``enable``
[mask, on], ``move`` [axis, target, trapezoid, unhomed], ``home`` [axis,
mode, index], ``heartbeat``, ``stop`` [mask], ``clear_fault`` [mask],
``counters``, ``store_report``, ``save``, ``drive`` [axis, duty], ``stats``, ``holds``, ``subscribe`` [every],
``unsubscribe``.

In-process watchers (the dashboard of ``serve --http``, torqueloop/host/dash/)
get every telemetry record the board sends, with the time it was read
(:meth:`SessionServer.add_watcher`).

Holding an axis: a client that enables an axis, moves it or homes it to
a switch holds it.  While any client holds an axis the server sends HEARTBEATs
(the link watchdog stays quiet however long a person takes between
commands); disabling an axis releases it; when the last client holding an
axis goes away (its process ended, its connection dropped) the server
disables that axis.
"""

from __future__ import annotations

import collections
import hashlib
import json
import os
import socket
import threading
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable

from torqueloop.spec import auth
from torqueloop.spec import protocol as P

from .client import Client, CommandRejected, ProtocolError

PROTOCOL, VERSION = "torqueloop-serve", 1
DEFAULT_PORT = 7130
KEEPALIVE_S = 0.15          # a HEARTBEAT this often keeps the firmware's link watchdog (>= 10 ms) quiet
PUMP_S = 0.005              # the server reads the board's link this long each time it holds it idle
                            # (a record reaches its watchers at most about this much after it arrived)
TELEMETRY_QUEUE = 2000      # records a client may fall behind before its oldest go (its own, counted)
SERVER_ENV = "TORQUELOOP_SERVER"
STATE_DIR_ENV = "TORQUELOOP_STATE_DIR"


# ---- finding a running server ------------------------------------------------------

def state_dir() -> Path:
    """Where ``serve`` leaves the address of each board it serves:
    ``$TORQUELOOP_STATE_DIR``, else ``$XDG_RUNTIME_DIR/torqueloop``, else
    ``~/.cache/torqueloop``."""
    if os.environ.get(STATE_DIR_ENV):
        return Path(os.environ[STATE_DIR_ENV])
    if os.environ.get("XDG_RUNTIME_DIR"):
        return Path(os.environ["XDG_RUNTIME_DIR"]) / "torqueloop"
    return Path.home() / ".cache" / "torqueloop"


def state_file(url: str) -> Path:
    return state_dir() / f"serve-{hashlib.sha256(url.encode()).hexdigest()[:16]}.json"


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True


def find_server(url: str) -> str | None:
    """The address (``HOST:PORT``) of a live server for the board at ``url``, from its state file."""
    path = state_file(url)
    try:
        st = json.loads(path.read_text())
    except (OSError, ValueError):
        return None
    if st.get("url") != url or not isinstance(st.get("pid"), int) or not _alive(st["pid"]):
        return None
    return str(st.get("addr"))


def split_addr(addr: str) -> tuple[str, int]:
    host, _, port = addr.rpartition(":")
    try:
        return host or "127.0.0.1", int(port)
    except ValueError:
        raise ValueError(f"server address {addr!r}: use HOST:PORT (e.g. 127.0.0.1:{DEFAULT_PORT})") from None


# ---- the server ------------------------------------------------------------------

@dataclass(eq=False)
class _Conn:
    sock: socket.socket
    name: str
    every: int = 0                  # telemetry: one record every `every` periods (0: not subscribed)
    skip: int = 0
    alive: bool = True
    wlock: threading.Lock = field(default_factory=threading.Lock)
    # telemetry waits here for this client's writer thread: the pump never blocks on a slow client
    tq: collections.deque = field(default_factory=lambda: collections.deque(maxlen=TELEMETRY_QUEUE))
    tq_ready: threading.Event = field(default_factory=threading.Event)
    dropped: int = 0

    def push(self, obj: dict) -> None:
        """Queue a telemetry line (never blocks; a full queue loses its oldest line, counted)."""
        if len(self.tq) == self.tq.maxlen:
            self.dropped += 1
        self.tq.append(obj)
        self.tq_ready.set()

    def write_queued(self) -> None:
        """This client's writer thread: its queued telemetry, until it goes."""
        while self.alive:
            self.tq_ready.wait(0.5)
            self.tq_ready.clear()
            while self.tq and self.alive:
                self.send(self.tq.popleft())

    def send(self, obj: dict) -> None:
        data = (json.dumps(obj, default=_jsonable) + "\n").encode()
        with self.wlock:
            if not self.alive:
                return
            try:
                self.sock.sendall(data)
            except OSError:
                self.alive = False


def _jsonable(o: Any) -> Any:
    if hasattr(o, "tolist"):
        return o.tolist()
    return str(o)


def error_obj(e: Exception) -> dict:
    out: dict[str, Any] = {"kind": type(e).__name__, "message": str(e)}
    if isinstance(e, CommandRejected):
        out.update(command=e.command, status=e.status, why=e.why)
    return out


class SessionServer:
    """Serves ``client`` (connected, with its key) to local clients on ``host:port``."""

    def __init__(self, client: Client, url: str, host: str = "127.0.0.1", port: int = DEFAULT_PORT, *,
                 log: Callable[[str], None] | None = None) -> None:
        self.client, self.url = client, url
        self.log = log or (lambda s: None)
        self.lock = threading.Lock()             # one command on the board at a time
        self.sock = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
        self.sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        self.sock.bind((host, port))
        self.sock.listen(16)
        self.addr = f"{host}:{self.sock.getsockname()[1]}"
        self.conns: set[_Conn] = set()
        self.holders: dict[int, set[_Conn]] = {a: set() for a in range(P.AXIS_COUNT)}
        self.board_every = 0
        self.watchers: list[tuple[int, Callable[[list[dict], float], None]]] = []
        self._stop = threading.Event()
        self._count = 0
        self.identity = dict(client.identity or client.identify())

    # ---- lifetime ----------------------------------------------------------------
    def serve_forever(self) -> None:
        pump = threading.Thread(target=self._pump_loop, name="tl-serve-pump", daemon=True)
        pump.start()
        self.sock.settimeout(0.2)
        try:
            while not self._stop.is_set():
                try:
                    s, peer = self.sock.accept()
                except socket.timeout:
                    continue
                except OSError:
                    break
                self._count += 1
                conn = _Conn(s, f"client {self._count} ({peer[0]}:{peer[1]})")
                threading.Thread(target=self._serve_conn, args=(conn,), name=f"tl-serve-{self._count}",
                                 daemon=True).start()
        finally:
            self._stop.set()
            pump.join(2)
            self.shutdown()

    def stop(self) -> None:
        self._stop.set()

    def shutdown(self) -> None:
        """Disable every held axis and close every connection (Ctrl-C on ``serve``)."""
        for c in list(self.conns):
            c.alive = False
            try:
                c.sock.shutdown(socket.SHUT_RDWR)
            except OSError:
                pass
        # under the board's lock, as a leaving client's release: each held axis is disabled
        # once, by whichever comes first, and never after the link is closed
        with self.lock:
            held = [a for a, h in self.holders.items() if h]
            for h in self.holders.values():
                h.clear()
            if held:
                try:
                    self.client.enable(sum(1 << a for a in held), False)
                    self.log(f"serve: disabled axes {held} (server stopping)")
                except ProtocolError as e:
                    self.log(f"serve: could not disable axes {held}: {e}")
        try:
            with self.lock:
                self.client.set_telemetry(0)
        except ProtocolError:
            pass
        self.sock.close()

    # ---- one client ----------------------------------------------------------------
    def _serve_conn(self, conn: _Conn) -> None:
        self.conns.add(conn)
        threading.Thread(target=conn.write_queued, name=f"{threading.current_thread().name}-tx",
                         daemon=True).start()
        self.log(f"serve: {conn.name} connected")
        conn.send({"type": "hello", "protocol": PROTOCOL, "version": VERSION, "board": self.url,
                   "identity": self.identity,
                   "key_id": auth.key_id(self.client.key) if self.client.key else None})
        f = conn.sock.makefile("rb")
        try:
            for line in f:
                if not conn.alive:
                    break
                if not line.strip():
                    continue
                try:
                    req = json.loads(line)
                    if not isinstance(req, dict):
                        raise ValueError("a request is a JSON object")
                except ValueError as e:
                    conn.send({"id": None, "error": {"kind": "BadRequest", "message": f"not a request: {e}"}})
                    continue
                conn.send(self._answer(conn, req))
        except OSError:
            pass
        finally:
            conn.alive = False
            self._release(conn)
            try:
                conn.sock.close()
            except OSError:
                pass

    def _answer(self, conn: _Conn, req: dict) -> dict:
        rid = req.get("id")
        method, params = req.get("method"), req.get("params") or {}
        fn = getattr(self, f"m_{method}", None) if isinstance(method, str) else None
        if fn is None or not isinstance(params, dict):
            return {"id": rid, "error": {"kind": "BadRequest",
                                         "message": f"unknown method {method!r} (docs/host.md, 'The session server')"}}
        try:
            return {"id": rid, "result": fn(conn, **params)}
        except TypeError as e:
            return {"id": rid, "error": {"kind": "BadRequest", "message": f"{method}: {e}"}}
        except (ProtocolError, ValueError, OSError) as e:
            return {"id": rid, "error": error_obj(e)}

    def _release(self, conn: _Conn) -> None:
        self.conns.discard(conn)
        with self.lock:                         # (shutdown: the same lock)
            orphaned = []
            for a, h in self.holders.items():
                if conn in h:
                    h.discard(conn)
                    if not h:
                        orphaned.append(a)
            if orphaned:
                try:
                    self.client.enable(sum(1 << a for a in orphaned), False)
                    self.log(f"serve: {conn.name} left holding axes {orphaned}: disabled them")
                except ProtocolError as e:
                    self.log(f"serve: could not disable axes {orphaned}: {e}")
        if conn.every:
            conn.every = 0
            if not self._stop.is_set():         # stopping: shutdown() ends the stream itself
                try:
                    self._retune()
                except ProtocolError as e:
                    self.log(f"serve: {e}")
        lost = f" (it lost {conn.dropped} telemetry lines it did not read in time)" if conn.dropped else ""
        self.log(f"serve: {conn.name} gone{lost}")

    def _hold(self, conn: _Conn, mask: int) -> None:
        for a in range(P.AXIS_COUNT):
            if mask & (1 << a):
                self.holders[a].add(conn)

    # ---- the board, one command at a time ------------------------------------------
    def _run(self, fn: Callable[[], Any]) -> Any:
        with self.lock:
            return fn()

    def m_identify(self, conn: _Conn) -> dict:
        self.identity = dict(self._run(self.client.identify))
        return self.identity

    def m_status(self, conn: _Conn, axis: int = 0) -> dict:
        return dict(self._run(lambda: self.client.status(axis)))

    def m_get_param(self, conn: _Conn, name: str, axis: int = 0) -> int:
        return self._run(lambda: self.client.get_param(name, axis))

    def m_set_param(self, conn: _Conn, name: str, value: int, axis: int = 0) -> int:
        return self._run(lambda: self.client.set_param(name, int(value), axis))

    def m_enable(self, conn: _Conn, mask: int, on: bool = True) -> None:
        self._run(lambda: self.client.enable(mask, bool(on)))
        if on:
            self._hold(conn, mask)
        else:
            for a in range(P.AXIS_COUNT):
                if mask & (1 << a):
                    self.holders[a].clear()

    def m_move(self, conn: _Conn, axis: int, target: int, trapezoid: bool = False, unhomed: bool = False) -> None:
        self._run(lambda: self.client.move(axis, int(target), bool(trapezoid), bool(unhomed)))
        self._hold(conn, 1 << axis)

    def m_home(self, conn: _Conn, axis: int, mode: str, index: bool = False) -> None:
        self._run(lambda: self.client.home(axis, mode, bool(index)))
        if mode != "here":               # homing to a switch moves the axis: this client now holds it
            self._hold(conn, 1 << axis)

    def m_heartbeat(self, conn: _Conn) -> None:
        self._run(self.client.heartbeat)

    def m_stop(self, conn: _Conn, mask: int) -> None:
        self._run(lambda: self.client.stop(mask))

    def m_clear_fault(self, conn: _Conn, mask: int) -> list[int]:
        return list(self._run(lambda: self.client.clear_fault(mask)))

    def m_counters(self, conn: _Conn) -> dict:
        return dict(self._run(self.client.counters))

    def m_store_report(self, conn: _Conn) -> dict | None:
        return self._run(self.client.store_report)

    def m_save(self, conn: _Conn) -> dict:
        return dict(self._run(self.client.save))

    def m_drive(self, conn: _Conn, axis: int, duty: int) -> None:
        """DRIVE: open-loop command ``duty`` (signed PWM steps) on an enabled axis; this client holds it."""
        self._run(lambda: self.client.drive(int(axis), int(duty)))
        self._hold(conn, 1 << axis)

    def m_stats(self, conn: _Conn) -> dict:
        return {k: v for k, v in vars(self.client.stats).items() if k != "text_sample"}

    def m_holds(self, conn: _Conn) -> dict:
        return {str(a): [c.name for c in h] for a, h in self.holders.items()}

    def m_subscribe(self, conn: _Conn, every: int = 1) -> int:
        if not 1 <= int(every) <= 65535:
            raise ValueError(f"subscribe: every {every} is outside [1, 65535]")
        conn.every, conn.skip = int(every), 0
        self._retune()
        return self.board_every

    def m_unsubscribe(self, conn: _Conn) -> None:
        conn.every = 0
        self._retune()

    # ---- telemetry and heartbeats ------------------------------------------------------
    def add_watcher(self, every: int, fn: Callable[[list[dict], float], None]) -> None:
        """``fn(records, t)`` from the pump's thread with every record the board
        sends (``t``: ``time.time()`` when they were read); the board streams at
        least every ``every`` periods from now on.  ``fn`` must not block."""
        self.watchers.append((int(every), fn))
        self._retune()

    def _retune(self) -> None:
        """The board streams at the fastest rate any subscriber asked for; each
        subscriber gets every k-th record of that stream."""
        want = min([c.every for c in self.conns if c.every and c.alive] + [e for e, _ in self.watchers],
                   default=0)
        if want != self.board_every:
            with self.lock:
                self.client.set_telemetry(want)
            self.board_every = want

    def _pump_loop(self) -> None:
        last_beat = 0.0
        while not self._stop.is_set():
            with self.lock:
                try:
                    self.client.pump(PUMP_S)
                    records = self.client.take_telemetry()
                    t_read = time.time()
                    now = time.monotonic()
                    if any(self.holders.values()) and now - last_beat >= KEEPALIVE_S:
                        self.client.heartbeat()
                        last_beat = now
                except ProtocolError as e:
                    self.log(f"serve: {e}")
                    records = []
            if records and self.board_every:
                for _, fn in self.watchers:
                    fn(records, t_read)
                for c in list(self.conns):
                    if not c.every or not c.alive:
                        continue
                    k = max(1, round(c.every / self.board_every))
                    for r in records:
                        if c.skip % k == 0:
                            c.push({"type": "telemetry", "record": r})
                        c.skip += 1
            # let the clients' commands in between two reads of the link
            time.sleep(0.002)


def write_state(url: str, addr: str) -> Path:
    """Leave this server's address where the CLI looks for it (0600, in a 0700 folder)."""
    path = state_file(url)
    path.parent.mkdir(parents=True, exist_ok=True, mode=0o700)
    tmp = path.with_suffix(".tmp")
    fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o600)
    with os.fdopen(fd, "w") as f:
        json.dump({"url": url, "addr": addr, "pid": os.getpid()}, f)
    os.replace(tmp, path)
    return path


def remove_state(url: str) -> None:
    path = state_file(url)
    try:
        st = json.loads(path.read_text())
        if st.get("pid") == os.getpid():
            path.unlink()
    except (OSError, ValueError):
        pass
