# SPDX-License-Identifier: MIT
"""A ``torqueloop`` command in a process of its own, as a person starts it
in a terminal: the tests and benches that end one with Ctrl-C use this.

A shell without job control (``cmd &`` in a script, ``nohup``, some CI
runners) starts its background commands with SIGINT ignored, every child
inherits that, and Python then installs no KeyboardInterrupt handler: a
test's SIGINT would reach a ``torqueloop serve`` that never hears it, and
the test would fail on how it was launched.  A terminal's foreground
command has SIGINT at its default action; this gives the child that,
whatever the test runner inherited."""

from __future__ import annotations

import signal
import subprocess
import sys
from typing import Any


def _sigint_default() -> None:
    signal.signal(signal.SIGINT, signal.SIG_DFL)


def cli(args: list[str], env: dict[str, str] | None = None, **popen: Any) -> subprocess.Popen:
    """``python -m torqueloop.cli ARGS`` with SIGINT at its default action (text mode unless told)."""
    popen.setdefault("text", True)
    return subprocess.Popen([sys.executable, "-m", "torqueloop.cli", *args], env=env,
                            preexec_fn=_sigint_default, **popen)
