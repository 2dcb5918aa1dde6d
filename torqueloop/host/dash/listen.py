# SPDX-License-Identifier: MIT
"""A dashboard client without a browser: what the server sends one WebSocket
in a time window (scripts that watch the stage, the latency bench, the tests
of who may do what).  Needs the ``dash`` extra (tornado)."""

from __future__ import annotations

import asyncio
import json
import time


async def listen(ws_url: str, seconds: float, requests: list[dict] = ()) -> tuple[list[tuple[float, str]], str | None]:
    """Send ``requests`` (the page's JSON operations) over a WebSocket to the
    dashboard, then collect for ``seconds`` every message with its arrival
    time (``time.time()``, ms).  Returns the messages and None, or no
    messages and the reason the handshake was refused."""
    from tornado.httpclient import HTTPClientError
    from tornado.websocket import websocket_connect

    try:
        ws = await websocket_connect(ws_url)
    except (HTTPClientError, OSError) as e:
        return [], str(e)
    for r in requests:
        await ws.write_message(json.dumps(r))
    got: list[tuple[float, str]] = []
    end = time.monotonic() + seconds
    while (left := end - time.monotonic()) > 0:
        try:
            m = await asyncio.wait_for(ws.read_message(), left)
        except asyncio.TimeoutError:
            break
        if m is None:
            break
        got.append((time.time() * 1000.0, m))
    ws.close()
    return got, None
