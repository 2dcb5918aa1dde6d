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
from dataclasses import dataclass
from typing import Any, Callable, Iterable, Iterator


class EngineError(RuntimeError):
    """A cluster that cannot be reached or used, in one line."""


@dataclass(frozen=True)
class Engine:
    """``address`` None: the local pool of ``jobs`` processes; else a Dask
    scheduler (``tcp://host:8786``)."""

    jobs: int = 2
    address: str | None = None

    @property
    def name(self) -> str:
        return f"dask distributed at {self.address}" if self.address else f"local pool of {self.jobs} processes"

    def map_unordered(self, fn: Callable[[Any], Any], items: Iterable[Any]) -> Iterator[tuple[Any, Any]]:
        items = list(items)
        if self.address is None:
            yield from _local(fn, items, self.jobs)
        else:
            yield from _dask(fn, items, self.address)


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
