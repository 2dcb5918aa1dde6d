# SPDX-License-Identifier: MIT
"""The tests marked slow (pyproject.toml: kept out of make test, which has to
fit 15 minutes): run here with pytest -m slow, their count, outcome and time
printed.  QUICK runs none."""

from __future__ import annotations

import subprocess
import sys
import time

from torqueloop.spec.repo import REPO_ROOT


def main() -> int:
    from bench import QUICK   # scripts/bench.py's flag (make bench QUICK=1)
    if QUICK:
        print("[bench_slow_tests] quick run: skipped (the slow tests take minutes)")
        return 0
    t0 = time.monotonic()
    r = subprocess.run([sys.executable, "-m", "pytest", "-q", "-m", "slow", "-p", "no:cacheprovider", "tb", "tests"],
                       cwd=REPO_ROOT, capture_output=True, text=True)
    tail = [ln for ln in r.stdout.splitlines() if ln.strip()][-1:] or ["(no output)"]
    print(f"[bench_slow_tests] pytest -m slow: {tail[0]} ({time.monotonic() - t0:.0f} s wall)", flush=True)
    if r.returncode not in (0, 5):    # 5: nothing collected
        print(r.stdout[-4000:], r.stderr[-2000:], sep="\n", flush=True)
        return 1
    return 0
