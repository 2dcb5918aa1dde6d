# SPDX-License-Identifier: MIT
"""``torqueloop sim`` in a process of its own, as a user starts it from a
second terminal: the URL it prints, and a Ctrl-C (SIGINT) when done."""

from __future__ import annotations

import json
import signal
import subprocess
from collections.abc import Iterator
from contextlib import contextmanager

from torqueloop import cli
from torqueloop.flow import terminal


@contextmanager
def sim_board(*args: str, env: dict[str, str] | None = None) -> Iterator[str]:
    """``python -m torqueloop.cli <args>`` (whose arguments include ``sim``);
    yields the ``socket://`` URL the board listens on."""
    p = terminal.cli(list(args), env, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL)
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


def run_cli(url: str, capsys, *args: str, rc: int = 0, json_out: bool = True) -> tuple[object, str]:
    """One ``torqueloop -u URL [--json] ARGS`` command in this process, as a
    user types it (``capsys``: pytest's fixture).  Asserts the exit status
    ``rc``, no traceback, and for a refusal (a failure that prints no result)
    one line on stderr.  Returns the last output line as JSON (or, with
    ``json_out=False``, the whole output; None after a refusal or when
    nothing was printed) and stderr."""
    capsys.readouterr()
    try:
        got = cli.main(["-u", url, *(["--json"] if json_out else []), *args])
    except SystemExit as e:          # argparse: a usage error
        got = e.code
    out, err = capsys.readouterr()
    assert got == rc, f"torqueloop {' '.join(args)} -> {got}\n{out}\n{err}"
    if rc:
        assert "Traceback" not in err, err
        if not out.strip():          # a refusal: one line says why
            assert len(err.strip().splitlines()) == 1, f"not one line: {err!r}"
            return None, err
    if not json_out:
        return out, err
    return (json.loads(out.strip().splitlines()[-1]) if out.strip() else None), err
