# SPDX-License-Identifier: MIT
"""Fold the wall times the last test run measured (build/test-durations.*.json,
written by conftest.py) into tests/durations.json, the file collection sorts
by (longest first).  Tests the run did not see keep their old figure; tests
that no longer exist are dropped only with --prune.

    .venv/bin/python scripts/test_durations.py [--prune]
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
DURATIONS = ROOT / "tests" / "durations.json"


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--prune", action="store_true", help="drop tests the last run did not measure")
    a = ap.parse_args(argv)
    runs = sorted((ROOT / "build").glob("test-durations.*.json"))
    if not runs:
        print("no measurements: run make test first (they land in build/test-durations.*.json)", file=sys.stderr)
        return 2
    measured: dict[str, float] = {}
    for f in runs:
        measured.update(json.loads(f.read_text()))
    old = {} if a.prune or not DURATIONS.exists() else json.loads(DURATIONS.read_text())
    merged = {**old, **measured}
    DURATIONS.write_text(json.dumps(dict(sorted(merged.items(), key=lambda kv: -kv[1])), indent=0) + "\n")
    total = sum(measured.values())
    print(f"{len(measured)} tests measured ({total / 60:.1f} test-minutes), {len(merged)} in {DURATIONS.relative_to(ROOT)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
