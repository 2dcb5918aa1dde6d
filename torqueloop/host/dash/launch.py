# SPDX-License-Identifier: MIT
"""``torqueloop serve --http [ADDR:PORT]``: the dashboard beside the session
server, with the tokens its address calls for (torqueloop/host/dash/access.py)."""

from __future__ import annotations

import socket
from pathlib import Path
from typing import Callable

from torqueloop.spec.units import BadValue

from ..serve import SessionServer
from .access import LOOPBACK, Access, TokenFileError, new_tokens, read_token_file

DEFAULT_HTTP = "127.0.0.1:7131"


def parse_http(spec: str) -> tuple[str, int]:
    """``ADDR:PORT``, ``:PORT``, ``PORT`` or ``ADDR`` -> (address, port)."""
    text = spec.strip()
    host, port = DEFAULT_HTTP.rsplit(":", 1)
    if text.isdigit():
        port = text
    elif text.startswith("[") and "]" in text:           # [::1]:7131
        host, _, rest = text[1:].partition("]")
        port = rest.removeprefix(":") or port
    elif text.count(":") == 1:
        h, port = text.split(":")
        host = h or host
    elif text:
        host = text
    try:
        p = int(port)
    except ValueError:
        raise BadValue(f"--http {spec!r}: give ADDR:PORT, e.g. {DEFAULT_HTTP}") from None
    if not 0 <= p <= 65535:
        raise BadValue(f"--http {spec!r}: port {p} is outside 0..65535")
    return host, p


def check_http(spec: str) -> tuple[str, int]:
    """``parse_http``, and the address must name this machine's kind of host
    (resolvable): a mistyped one is refused before the board is touched."""
    host, port = parse_http(spec)
    try:
        socket.getaddrinfo(host, port, type=socket.SOCK_STREAM)
    except (socket.gaierror, UnicodeError) as e:
        raise BadValue(f"--http {spec!r}: {host!r} is not an address this machine can listen on ({e})") from None
    return host, port


def start(srv: SessionServer, spec: str, token_file: str | None, say: Callable[[str], None]) -> Callable[[], None]:
    """Start the dashboard for ``srv``; prints its address (and tokens) with
    ``say``; returns the function that stops it."""
    host, port = parse_http(spec)
    try:
        from .web import Dashboard
    except ImportError as e:
        raise BadValue(f"--http needs the dashboard's packages ({e.name} is missing): "
                       "pip install 'torqueloop[dash]'") from None
    if token_file:
        try:
            tokens = read_token_file(Path(token_file))
        except TokenFileError as e:
            raise BadValue(str(e)) from None
    else:
        tokens = {} if host in LOOPBACK else new_tokens()
    dash = Dashboard(srv, Access(tokens, host, port))
    try:
        url = dash.start()
    except OSError as e:
        raise BadValue(f"--http {spec}: cannot listen there ({e.strerror or e})") from None
    if not tokens:
        say(f"dashboard: {url} (this machine only, no token needed)")
    else:
        shown = url.replace("0.0.0.0", socket.gethostname()) if host in ("0.0.0.0", "::") else url
        say(f"dashboard on {url}: every page needs a token" + (f" (from {token_file})" if token_file else ""))
        for role in ("command", "watch"):
            if role in tokens:
                say(f"  {role + ':':9}{shown}?token={tokens[role]}")
    return dash.stop
