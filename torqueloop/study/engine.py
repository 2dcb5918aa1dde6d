# SPDX-License-Identifier: MIT
"""Where a study's independent runs execute: the local process pool (the
default), or a Dask distributed cluster when given a scheduler's address.

Both engines take a picklable function and a list of picklable jobs and
yield ``(job, result)`` as runs finish, in whatever order they finish; the
study orders its report itself, so the report is the same whichever engine
ran it (tests/test_engine.py compares them).

Why Dask distributed: it is what lab PCs and batch systems already run
(``dask scheduler`` / ``dask worker`` by hand, or dask-jobqueue under
SLURM, PBS, SGE), it ships Python functions and their arguments by
pickling, as the local pool does, and ``Client.map`` / ``as_completed``
are the pool's ``imap_unordered``.  Workers import torqueloop from their own
install (a clone with ``make setup`` on each machine); each builds what a
run needs once, keyed by the inputs' digest, as a local run does (the
firmware and the Verilator harness are cached under build/ by
torqueloop.flow.firmware and torqueloop.sim.native).  distributed is an
optional dependency (``pip install '.[cluster]'``); without it only the
local pool exists, and asking for a cluster says so in one line.
"""

from __future__ import annotations

import multiprocessing as mp
import time
from dataclasses import dataclass
from typing import Any, Callable, Iterable, Iterator, Sequence


class EngineError(RuntimeError):
    """A cluster that cannot be reached or used, in one line."""


@dataclass(frozen=True)
class Engine:
    """``address`` None: the local pool of ``jobs`` processes; else a Dask
    scheduler (``tcp://host:8786``)."""

    jobs: int = 2
    address: str | None = None

    @property
    def workers(self) -> int | None:
        """Runs at once: the pool's processes (a cluster's are not known here)."""
        return self.jobs if self.address is None else None

    @property
    def name(self) -> str:
        return f"dask distributed at {self.address}" if self.address else f"local pool of {self.jobs} processes"

    def map_unordered(self, fn: Callable[[Any], Any], items: Iterable[Any]) -> Iterator[tuple[Any, Any]]:
        items = list(items)
        if self.address is None:
            yield from _local(fn, items, self.jobs)
        else:
            yield from _dask(fn, items, self.address)


class Progress:
    """The time left of a batch of runs of unequal cost, for a stage's progress
    lines.  ``costs``: each run's expected cost, in the order the engine hands
    the runs out, in one unit of the caller's (simulated seconds times a factor
    per kind of run); ``workers``: how many run at once (None: unknown).

    With ``workers`` known the local pool's schedule is replayed: the first
    ``workers`` runs start at once and each finished run's worker takes the
    next; a worker's speed (cost per second) is learnt from the finished runs'
    own seconds; the time left is when the last run would end if the runs in
    flight and those still queued went at that speed.  So the first long runs
    to finish no longer make the rest look as long (the plain elapsed / k x
    (n - k) read 30 hours after make run's first RTL arm, for a stage with 40
    minutes left).  Without ``workers`` (a cluster): elapsed x (cost left /
    cost done)."""

    def __init__(self, costs: Sequence[float], workers: int | None) -> None:
        self.costs = [float(c) for c in costs]
        self.workers = workers
        self.cost_done = 0.0
        self.busy_done = 0.0
        self.t0 = time.monotonic()
        n = min(workers or 0, len(self.costs))
        self.running: dict[int, float] = {k: 0.0 for k in range(n)}    # run -> its start, seconds after t0
        self.queued = n                                                 # the next run a worker takes

    @property
    def elapsed_s(self) -> float:
        return time.monotonic() - self.t0

    def done(self, cost: float, busy_s: float) -> float:
        """A run of ``cost`` finished after ``busy_s`` on its worker; the seconds left, estimated."""
        self.cost_done += cost
        self.busy_done += max(busy_s, 1e-3)
        el = self.elapsed_s
        if not self.workers:
            return el * max(0.0, sum(self.costs) - self.cost_done) / self.cost_done
        if self.running:     # which run: the earliest started of those in flight with the nearest cost
            k = min(self.running, key=lambda j: (abs(self.costs[j] - cost), self.running[j]))
            del self.running[k]
        if self.queued < len(self.costs):
            self.running[self.queued] = el
            self.queued += 1
        speed = self.cost_done / self.busy_done
        free = sorted(max(el, t + self.costs[j] / speed) for j, t in self.running.items())
        free += [el] * (self.workers - len(free))
        for c in self.costs[self.queued:]:
            free.sort()
            free[0] += c / speed
        return max(free) - el

    def line(self, cost: float, busy_s: float) -> str:
        """``done`` as a progress line's tail: "12 min so far, about 40 min left"."""
        left = self.done(cost, busy_s)
        return f"{human_s(self.elapsed_s)} so far, about {human_s(left)} left"


def human_s(s: float) -> str:
    """Seconds as a person reads a duration: 45 s, 12 min, 2 h 05 min."""
    if s < 90:
        return f"{s:.0f} s"
    m = round(s / 60)
    return f"{m} min" if m < 90 else f"{m // 60} h {m % 60:02d} min"


def _pair(fn: Callable[[Any], Any], item: Any) -> tuple[Any, Any]:
    return item, fn(item)


class _Paired:
    """``item -> (item, fn(item))``, picklable for the pool (a closure is not)."""

    def __init__(self, fn: Callable[[Any], Any]) -> None:
        self.fn = fn

    def __call__(self, item: Any) -> tuple[Any, Any]:
        return _pair(self.fn, item)


def _local(fn: Callable[[Any], Any], items: list, jobs: int) -> Iterator[tuple[Any, Any]]:
    if jobs <= 1 or len(items) <= 1:
        for it in items:
            yield _pair(fn, it)
        return
    with mp.get_context("fork").Pool(min(jobs, len(items))) as pool:
        yield from pool.imap_unordered(_Paired(fn), items, chunksize=1)


def _dask(fn: Callable[[Any], Any], items: list, address: str) -> Iterator[tuple[Any, Any]]:
    try:
        from distributed import Client, as_completed
    except ImportError:
        raise EngineError("a cluster needs Dask distributed: pip install 'torqueloop[cluster]'") from None
    try:
        client = Client(address, timeout="10s")
    except (OSError, TimeoutError) as e:
        raise EngineError(f"no Dask scheduler answers at {address} ({e})") from None
    try:
        futures = client.map(_Paired(fn), items, pure=False)
        for fut in as_completed(futures):
            yield fut.result()
    finally:
        client.close()
