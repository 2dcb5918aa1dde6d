# SPDX-License-Identifier: MIT
"""``torqueloop sim`` in a process of its own, as a user starts it from a
second terminal: the URL it prints, and a Ctrl-C (SIGINT) when done."""

from __future__ import annotations

import signal
import subprocess
import sys
from collections.abc import Iterator
from contextlib import contextmanager


@contextmanager
def sim_board(*args: str, env: dict[str, str] | None = None) -> Iterator[str]:
    """``python -m torqueloop.cli <args>`` (whose arguments include ``sim``);
    yields the ``socket://`` URL the board listens on."""
    p = subprocess.Popen([sys.executable, "-m", "torqueloop.cli", *args], stdout=subprocess.PIPE,
                         stderr=subprocess.DEVNULL, text=True, env=env)
    try:
        line = p.stdout.readline()
        assert "socket://" in line, line
        yield line.split()[line.split().index("on") + 1]
    finally:
        p.send_signal(signal.SIGINT)
        try:
            p.wait(5)
        except subprocess.TimeoutExpired:
            p.kill()
