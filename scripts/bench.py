#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""make bench: run every benchmark in scripts/benches/ (bench_*.py, each with
a main() that prints its numbers) in name order, or only those named.

    scripts/bench.py [NAME ...]        # all, or those whose name contains NAME
    scripts/bench.py --quick [NAME ..] # make bench QUICK=1: shortened runs, a first look
    scripts/bench.py --list            # import every benchmark and list it (make test runs this)

A benchmark reads ``bench.QUICK`` to shorten itself; the numbers of a quick
run are for a first look, not for the docs."""

from __future__ import annotations

import argparse
import importlib
import sys
import time
from pathlib import Path
from types import ModuleType

BENCH_DIR = Path(__file__).resolve().parent / "benches"

#: set by --quick before any benchmark runs
QUICK = False


def load(f: Path) -> ModuleType:
    """A benchmark by name: scripts/benches/ is a namespace package beside
    this script, which Python puts first on the path."""
    mod = importlib.import_module(f"{BENCH_DIR.name}.{f.stem}")
    if not callable(getattr(mod, "main", None)):
        raise TypeError(f"{f.name} has no main()")
    return mod


def main(argv: list[str] | None = None) -> int:
    global QUICK
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("only", nargs="*", help="substring of benchmark names to run")
    ap.add_argument("--quick", action="store_true", help="shortened runs (make bench QUICK=1)")
    ap.add_argument("--list", action="store_true", help="import every benchmark and list it; run nothing")
    args = ap.parse_args(argv)
    # the benchmarks `from bench import ...`: this module, with its flags, not a second copy
    sys.modules.setdefault("bench", sys.modules[__name__])
    QUICK = sys.modules["bench"].QUICK = args.quick
    files = sorted(BENCH_DIR.glob("bench_*.py"))
    if args.only:
        files = [f for f in files if any(o in f.stem for o in args.only)]
    if not files:
        print("[bench] no benchmark matched", file=sys.stderr)
        return 1
    if args.list:
        bad = 0
        for f in files:
            try:
                doc = (load(f).__doc__ or "").strip().splitlines() or ["(no description)"]
                print(f"{f.stem:28s} {doc[0]}")
            except Exception as e:   # noqa: BLE001 - every broken benchmark is reported
                print(f"[bench] {f.stem} does not load: {e!r}", file=sys.stderr)
                bad += 1
        return 1 if bad else 0
    failed = 0
    t_all = time.monotonic()
    for f in files:
        print(f"\n===== {f.stem}{' (quick)' if QUICK else ''} =====", flush=True)
        t0 = time.monotonic()
        try:
            rc = load(f).main()
        except Exception as e:  # report and go on with the others
            print(f"[bench] {f.stem} raised {e!r}", file=sys.stderr)
            rc = 1
        failed += bool(rc)
        print(f"[bench] {f.stem} {'FAILED' if rc else 'done'} in {time.monotonic() - t0:.1f} s", flush=True)
    print(f"\n[bench] {len(files) - failed} of {len(files)} benchmarks done, {failed} failed, "
          f"{time.monotonic() - t_all:.0f} s", flush=True)
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
