# SPDX-License-Identifier: MIT
"""The telemetry's fan-out to the pages of the dashboard.

Every record the board sends becomes one *row* (:data:`ROW`: a server
sequence number, the time the server read it, the board's time and each
axis's fields) in a history ring and in the queue of each page.  A page's
queue is bounded: when a page does not take its rows (a slow network, a
stalled tab) the oldest of *its* rows go, counted in its ``dropped``; the
link, the other pages and the CLI clients do not wait for it.  A page that
reconnects names the last row it has and gets the rows after it from the
history: a dropped connection loses no row the history still holds.
"""

from __future__ import annotations

import collections
import threading
from dataclasses import dataclass, field
from typing import Callable

from torqueloop.spec import protocol as P

#: the fields of one axis in a row, in order (the telemetry frame's, from protocol.toml)
AXIS_FIELDS: tuple[str, ...] = tuple(name for name, _ in P.SPEC["telemetry"]["axis"])
#: a row: [seq, t_rx_ms, time_us, axis 0's AXIS_FIELDS..., axis 1's ...]
ROW: tuple[str, ...] = ("seq", "t_rx_ms", "time_us") + tuple(
    f"{f}{a}" for a in range(P.AXIS_COUNT) for f in AXIS_FIELDS)

HISTORY_ROWS = 24_000       # 10 min at the paper's 25 ms period
QUEUE_ROWS = 2_000          # a page may fall this far behind before its oldest rows go


def row_of(seq: int, t_rx: float, rec: dict) -> list:
    out: list = [seq, round(t_rx * 1000.0, 3), rec["time_us"]]
    for ax in rec["axes"]:
        out += [ax[f] for f in AXIS_FIELDS]
    return out


@dataclass(eq=False)
class Page:
    """One page's view of the stream."""
    name: str
    wake: Callable[[], None]            # called (from any thread) when rows wait for this page
    queue_rows: int = QUEUE_ROWS
    q: collections.deque = field(init=False)
    dropped: int = 0                    # rows this page lost to its full queue
    sent: int = 0

    def __post_init__(self) -> None:
        self.q = collections.deque(maxlen=self.queue_rows)


class Hub:
    def __init__(self, history_rows: int = HISTORY_ROWS) -> None:
        self.lock = threading.Lock()
        self.changed = threading.Condition(self.lock)
        self.history: collections.deque[list] = collections.deque(maxlen=history_rows)
        self.pages: set[Page] = set()
        self.seq = 0

    def feed(self, records: list[dict], t_rx: float) -> None:
        """Records as the session server read them at ``t_rx`` (``time.time()``)."""
        with self.lock:
            rows = []
            for r in records:
                self.seq += 1
                rows.append(row_of(self.seq, t_rx, r))
            self.history.extend(rows)
            pages = list(self.pages)
            for p in pages:
                over = len(p.q) + len(rows) - p.queue_rows
                if over > 0:
                    p.dropped += min(over, len(p.q) + len(rows))
                p.q.extend(rows)
            self.changed.notify_all()
        for p in pages:
            p.wake()

    def attach(self, page: Page, since: int | None, replay: int) -> tuple[list[list], int]:
        """Register ``page``; (the rows it missed, rows the history no longer
        held).  ``since``: the last row it has (None: a new page, which gets the
        last ``replay`` rows)."""
        with self.lock:
            hist = list(self.history)
            if since is None:
                rows = hist[-replay:] if replay else []
                lost = 0
            else:
                rows = [r for r in hist if r[0] > since]
                first = rows[0][0] if rows else self.seq + 1
                lost = max(0, first - since - 1)
            self.pages.add(page)
        return rows, lost

    def detach(self, page: Page) -> None:
        with self.lock:
            self.pages.discard(page)

    def take(self, page: Page) -> list[list]:
        with self.lock:
            rows = list(page.q)
            page.q.clear()
            page.sent += len(rows)
        return rows

    def rows_since(self, seq: int) -> list[list]:
        with self.lock:
            return [r for r in self.history if r[0] > seq]

    def wait_rows(self, seq: int, until: Callable[[list[list]], bool], timeout: float) -> list[list]:
        """Wait (at most ``timeout`` s) until the rows after ``seq`` satisfy ``until``; those rows."""
        with self.changed:
            self.changed.wait_for(lambda: until([r for r in self.history if r[0] > seq]), timeout)
            return [r for r in self.history if r[0] > seq]
