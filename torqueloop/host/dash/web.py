# SPDX-License-Identifier: MIT
"""The dashboard's web server: Tornado (HTTP and WebSocket) in a thread of
``torqueloop serve``, beside its JSON-lines port.

Routes: ``/`` the page (``?token=T`` sets a cookie and redirects, so the
token leaves the address bar), ``/api/config`` what the page needs to draw
(figures, row layout, units, fault names), ``/static/bokeh/`` BokehJS from
the bokeh wheel, ``/static/dash/`` the page's own glue, ``/ws`` the
WebSocket: rows of telemetry and status out, requests in.  Every route
checks :class:`~.access.Access` first.

Messages to a page (JSON): ``{"t": "hello", "role", "last_seq", "lost",
"rows"}`` (the rows it missed), ``{"t": "rows", "rows", "dropped"}``,
``{"t": "status", "axes", "holds", "pages"}``, ``{"t": "reply", "id", "ok",
"result" | "error"}``.  From a page: ``{"id", "op", "params"}``
(:data:`.actions.Actions.OPS`).
"""

from __future__ import annotations

import asyncio
import json
import logging
import math
import threading
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path
from typing import Any

import tornado.ioloop
import tornado.netutil
import tornado.web
import tornado.websocket
from bokeh.util.paths import static_path as bokeh_static
from tornado.httpserver import HTTPServer

from torqueloop.spec import protocol as P
from torqueloop.spec import units

from ..client import FAULT_DESC, CommandRejected, ProtocolError
from ..serve import SessionServer
from . import plots
from .access import Access
from .actions import Actions, PageConn
from .hub import ROW, Hub, Page

DEFAULT_HTTP_PORT = 7131
STATUS_S = 0.5              # how often the pages get the axes' state (STATUS of each axis)
MAX_RATE_HZ = 200           # the dashboard asks for at most this many records a second
REPLAY_ROWS = 2_000         # a new page starts with this much of the history
COOKIE = "tl_token"
STATIC = Path(__file__).with_name("static")


def telemetry_every(period_us: int) -> int:
    """Every how many control periods a record, for at most MAX_RATE_HZ records a second."""
    return max(1, math.ceil(1e6 / (period_us * MAX_RATE_HZ)))


class _Auth:
    """What every handler checks first."""
    dash: "Dashboard"

    def token(self) -> str | None:
        h = self  # type: ignore[assignment]
        bearer = (h.request.headers.get("Authorization") or "").removeprefix("Bearer ").strip()
        return h.get_query_argument("token", None) or h.get_cookie(COOKIE) or bearer or None

    def role(self) -> str | None:
        if not self.dash.access.host_ok(self.request.headers.get("Host")):   # type: ignore[attr-defined]
            return None
        return self.dash.access.role(self.token())


class _Base(_Auth, tornado.web.RequestHandler):
    def initialize(self, dash: "Dashboard") -> None:
        self.dash = dash

    def prepare(self) -> None:
        if self.role() is None:
            self.set_status(401)
            self.set_header("Content-Type", "text/plain; charset=utf-8")
            self.finish("This torqueloop dashboard needs its token: open the URL that `torqueloop serve --http` "
                        "printed (watch or command).\n")

    def set_default_headers(self) -> None:
        self.set_header("Cache-Control", "no-store")
        self.set_header("X-Frame-Options", "DENY")
        self.set_header("Referrer-Policy", "no-referrer")


class IndexHandler(_Base):
    def get(self) -> None:
        tok = self.get_query_argument("token", None)
        if tok and not self.dash.access.open:
            self.set_cookie(COOKIE, tok, httponly=True, samesite="Strict", path="/")
            self.redirect("/")
            return
        self.set_header("Content-Type", "text/html; charset=utf-8")
        self.write((STATIC / "index.html").read_bytes())


class NoIcon(_Base):
    def get(self) -> None:
        self.set_status(204)


class ConfigHandler(_Base):
    def get(self) -> None:
        self.set_header("Content-Type", "application/json")
        self.write(json.dumps(self.dash.config(self.role() or "watch")))


class StaticHandler(_Auth, tornado.web.StaticFileHandler):
    def initialize(self, path: str, dash: "Dashboard") -> None:   # type: ignore[override]
        super().initialize(path)
        self.dash = dash

    def prepare(self) -> None:
        if self.role() is None:
            raise tornado.web.HTTPError(401)


class PageSocket(_Auth, tornado.websocket.WebSocketHandler):
    def initialize(self, dash: "Dashboard") -> None:
        self.dash = dash
        self.page: Page | None = None
        self.conn: PageConn | None = None
        self.writing = False

    def check_origin(self, origin: str) -> bool:
        return super().check_origin(origin) and self.dash.access.host_ok(self.request.headers.get("Host"))

    async def get(self, *args: Any, **kwargs: Any) -> None:
        if self.role() is None:
            self.set_status(401)
            self.finish("token needed\n")
            return
        await super().get(*args, **kwargs)

    def open(self) -> None:
        self.my_role = self.role() or "watch"
        d = self.dash
        d.count += 1
        name = f"page {d.count} ({self.request.remote_ip}, {self.my_role})"
        self.conn = PageConn(name)
        self.page = Page(name, wake=lambda: d.loop.call_soon_threadsafe(self.push_rows))
        since_arg = self.get_query_argument("since", "") or ""
        since = int(since_arg) if since_arg.isdigit() else None
        rows, lost = d.hub.attach(self.page, since, REPLAY_ROWS)
        d.sockets.add(self)
        d.srv.log(f"dashboard: {name} connected")
        self.send({"t": "hello", "role": self.my_role, "rows": rows, "lost": lost, "last_seq": d.hub.seq})
        if d.last_status is not None:
            self.send(d.last_status)

    def send(self, obj: dict) -> None:
        try:
            self.write_message(json.dumps(obj, default=str))
        except tornado.websocket.WebSocketClosedError:
            pass

    def push_rows(self) -> None:
        """Send this page's queued rows, one message at a time: while the last
        has not left (a slow page), its rows wait in its bounded queue."""
        if self.writing or self.page is None or self.ws_connection is None:
            return
        rows = self.dash.hub.take(self.page)
        if not rows:
            return
        try:
            fut = self.write_message(json.dumps({"t": "rows", "rows": rows, "dropped": self.page.dropped}))
        except tornado.websocket.WebSocketClosedError:
            return
        self.writing = True

        def done(_: Any) -> None:
            self.writing = False
            if self.page is not None and self.page.q:
                self.push_rows()
        fut.add_done_callback(done)

    async def on_message(self, message: str | bytes) -> None:
        try:
            req = json.loads(message)
            rid, op, params = req.get("id"), str(req.get("op")), dict(req.get("params") or {})
        except (ValueError, AttributeError, TypeError):
            self.send({"t": "reply", "id": None, "ok": False, "error": "not a request"})
            return
        if not self.dash.access.may(self.my_role, op):
            self.send({"t": "reply", "id": rid, "ok": False,
                       "error": f"{op}: this page may only watch and STOP (open it with the command token)"})
            return
        loop = asyncio.get_running_loop()
        try:
            result = await loop.run_in_executor(self.dash.pool, self.dash.actions.run, self.conn, op, params)
            self.send({"t": "reply", "id": rid, "ok": True, "result": result})
        except (ProtocolError, ValueError, TypeError, OSError) as e:
            msg = str(e) if not isinstance(e, TypeError) else f"{op}: bad request ({e})"
            self.send({"t": "reply", "id": rid, "ok": False, "error": msg,
                       "rule": e.rule if isinstance(e, CommandRejected) else None})

    def on_close(self) -> None:
        d = self.dash
        d.sockets.discard(self)
        if self.page is not None:
            d.hub.detach(self.page)
        if self.conn is not None:
            self.conn.alive = False
            conn, self.conn = self.conn, None
            d.pool.submit(d.srv._release, conn)      # an axis only this page held is disabled


class Dashboard:
    """The web server of one :class:`SessionServer`; :meth:`start` runs it in a thread."""

    def __init__(self, srv: SessionServer, access: Access) -> None:
        self.srv, self.access = srv, access
        self.hub = Hub()
        self.actions = Actions(srv, self.hub)
        self.pool = ThreadPoolExecutor(max_workers=4, thread_name_prefix="tl-dash")
        self.sockets: set[PageSocket] = set()
        self.count = 0
        self.last_status: dict | None = None
        self._status_busy = False
        self.loop: asyncio.AbstractEventLoop | None = None
        self._ready = threading.Event()
        self._error: BaseException | None = None
        self._figures = plots.layout()
        self._scales = self.actions.scales()
        self.port = access.port

    def config(self, role: str) -> dict:
        return {"role": role, "axes": P.AXIS_COUNT, "row": ROW, "plots": self._figures,
                "columns": plots.COLUMNS, "window_s": plots.WINDOW_S, "scales": self._scales,
                "units": list(units.POSITION_UNITS), "faults": {n: FAULT_DESC[n] for n in P.FAULT},
                "fault_bits": dict(P.FAULT), "board": self.srv.url,
                "identity": {k: v for k, v in (self.srv.identity or {}).items() if k != "status"}}

    def app(self) -> tornado.web.Application:
        kw = {"dash": self}
        return tornado.web.Application([
            (r"/", IndexHandler, kw),
            (r"/api/config", ConfigHandler, kw),
            (r"/favicon.ico", NoIcon, kw),
            (r"/ws", PageSocket, kw),
            (r"/static/bokeh/(.*)", StaticHandler, {"path": bokeh_static(), **kw}),
            (r"/static/dash/(.*)", StaticHandler, {"path": str(STATIC), **kw}),
        ], websocket_ping_interval=10)

    # ---- lifetime -----------------------------------------------------------------------
    def start(self) -> str:
        """Listen (raises OSError if the address is taken) and serve in a thread; the address."""
        threading.Thread(target=self._run, name="tl-dash-web", daemon=True).start()
        self._ready.wait(30)
        if self._error is not None:
            raise self._error
        every = telemetry_every(self.srv._run(lambda: self.srv.client.get_param("PERIOD_US")))
        self.srv.add_watcher(every, self.hub.feed)
        host = f"[{self.access.host}]" if ":" in self.access.host else self.access.host
        return f"http://{host}:{self.port}/"

    def _run(self) -> None:
        logging.getLogger("tornado.access").setLevel(logging.ERROR)     # a refused request is no news to log
        loop = asyncio.new_event_loop()
        asyncio.set_event_loop(loop)
        self.loop = loop
        try:
            server = HTTPServer(self.app())
            socks = tornado.netutil.bind_sockets(self.access.port, self.access.host)
            server.add_sockets(socks)
            self.port = socks[0].getsockname()[1]
        except BaseException as e:     # noqa: BLE001 - handed to start(), which raises it
            self._error = e
            self._ready.set()
            return
        tornado.ioloop.PeriodicCallback(self._poll_status, STATUS_S * 1000).start()
        self._ready.set()
        loop.run_forever()

    def stop(self) -> None:
        if self.loop is not None:
            self.loop.call_soon_threadsafe(self.loop.stop)
        self.pool.shutdown(wait=False, cancel_futures=True)

    # ---- the state of the axes, for every page -----------------------------------------
    def _poll_status(self) -> None:
        if not self.sockets or self._status_busy:
            return
        self._status_busy = True
        fut = self.pool.submit(self._status)

        def done(f: Any) -> None:
            self._status_busy = False
            try:
                msg = f.result()
            except Exception as e:          # noqa: BLE001 - the board's trouble, shown on the pages
                msg = {"t": "status", "error": str(e)}
            self.last_status = msg
            for s in list(self.sockets):
                own = dict(msg, dropped=s.page.dropped if s.page else 0)
                self.loop.call_soon_threadsafe(s.send, own)
        fut.add_done_callback(done)

    def _status(self) -> dict:
        return {"t": "status", "axes": self.actions.status(), "holds": self.srv.m_holds(None),
                "pages": len(self.sockets), "link": self.srv.m_stats(None)}

