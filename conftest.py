# SPDX-License-Identifier: MIT
"""pytest, however started (make test, .venv/bin/python -m pytest, pytest in
an activated environment): the project's tools first on PATH
(torqueloop/flow/tools.py), so every test sees the same Verilator.

The longest tests start first.  make test spreads the tests over both cores
(pytest-xdist, ``--dist load``: the scheduler hands them out in collection
order), so a 4-minute bench collected last leaves one core idle while it
runs alone.  tests/durations.json holds each test's measured wall time;
collection sorts by it, longest first (the same order on every worker, as
xdist requires).  A test it does not know yet counts as the median.  Every
run writes what it measured to build/test-durations.<worker>.json;
``make test-durations`` folds that into tests/durations.json.

xdist's load scheduler starts each worker on a block of consecutive tests
(a quarter of its share: 89 of 717), so sorted longest first, the first
worker got every long bench (1 404 s of recorded time against 133 s) and
the second sat idle for its last 15 minutes.  One test at a time
(``--maxschedchunk 1``, unless given) keeps two queued per worker and hands
out the rest as workers free up.
"""

from __future__ import annotations

import json
import os
import statistics
import time
from pathlib import Path

from torqueloop.flow.tools import use_project_tools

use_project_tools()

_ROOT = Path(__file__).resolve().parent
DURATIONS = _ROOT / "tests" / "durations.json"
MEASURED = _ROOT / "build"


def _known() -> dict[str, float]:
    try:
        return {str(k): float(v) for k, v in json.loads(DURATIONS.read_text()).items()}
    except (OSError, ValueError):
        return {}


def pytest_configure(config):
    # the controller builds its scheduler after this; a value given on the command line wins
    if getattr(config.option, "maxschedchunk", 0) is None:
        config.option.maxschedchunk = 1
    _no_reconnect_grace()


def _no_reconnect_grace() -> None:
    """pyserial's socket:// port sleeps 0.3 s after closing its socket ("in
    case of quick reconnects, give the server some time": the RN-XV's, on a
    real bench).  The tests run the torqueloop command in their own process
    hundreds of times against ``torqueloop sim``, which sees the old
    connection end before it takes the next one, so that sleep was only
    idle worker time; here it is skipped, in the tests' process only (the
    tool a user runs keeps it; commands run as subprocesses keep it too)."""
    try:
        from serial.urlhandler import protocol_socket
    except ImportError:
        return

    class _Time:
        """The time module for protocol_socket, whose only use of it is that sleep."""

        def __getattr__(self, name: str):
            return getattr(time, name)

        @staticmethod
        def sleep(seconds: float) -> None:
            pass

    protocol_socket.time = _Time()


def pytest_collection_modifyitems(session, config, items):
    known = _known()
    if not known:
        return
    default = statistics.median(known.values())
    items.sort(key=lambda item: -known.get(item.nodeid, default))     # stable: ties keep file order


_phases: dict[str, float] = {}


def pytest_runtest_makereport(item, call):
    _phases[item.nodeid] = _phases.get(item.nodeid, 0.0) + (call.stop - call.start)


def pytest_sessionfinish(session, exitstatus):
    # one file per process (each xdist worker records the tests it ran); make test-durations folds them
    if not _phases:
        return
    worker = os.environ.get("PYTEST_XDIST_WORKER", "main")
    MEASURED.mkdir(parents=True, exist_ok=True)
    path = MEASURED / f"test-durations.{worker}.json"
    path.write_text(json.dumps({k: round(v, 2) for k, v in sorted(_phases.items())}, indent=0) + "\n")
