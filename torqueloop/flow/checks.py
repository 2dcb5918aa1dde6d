# SPDX-License-Identifier: MIT
"""How every ``make lint`` check ends: each finding on its own line, then one
summary line that starts ok or FAIL, and the exit status."""

from __future__ import annotations

from typing import Iterable


def finish(tag: str, findings: Iterable[object], summary: str) -> int:
    """Print ``[tag] finding`` per finding and ``[tag] ok|FAIL summary``;
    0 when there is none, 1 otherwise."""
    found = list(findings)
    for f in found:
        print(f"[{tag}] {f}")
    print(f"[{tag}] {'FAIL' if found else 'ok  '} {summary}")
    return 1 if found else 0
