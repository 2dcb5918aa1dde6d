#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""make bench: run every benchmark in scripts/benches/ (bench_*.py, each with
a main() that prints its numbers) in name order, or only those named."""

from __future__ import annotations

import argparse
import importlib
import importlib.util
import sys
import time
from pathlib import Path

BENCH_DIR = Path(__file__).resolve().parent / "benches"
TB_DIR = Path(__file__).resolve().parent.parent / "tb"


def tb_module(folder: str, name: str):
    """A test bench module (tb/<folder>/<name>.py) whose cocotb tests a
    benchmark runs: its folder goes on sys.path, where the simulator's Python
    (which gets this process's path) finds the module by name too."""
    d = str(TB_DIR / folder)
    if d not in sys.path:
        sys.path.insert(0, d)
    return importlib.import_module(name)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("only", nargs="*", help="substring of benchmark names to run")
    args = ap.parse_args()
    files = sorted(BENCH_DIR.glob("bench_*.py"))
    if args.only:
        files = [f for f in files if any(o in f.stem for o in args.only)]
    if not files:
        print("[bench] no benchmark matched", file=sys.stderr)
        return 1
    failed = 0
    for f in files:
        print(f"\n===== {f.stem} =====", flush=True)
        spec = importlib.util.spec_from_file_location(f.stem, f)
        mod = importlib.util.module_from_spec(spec)
        assert spec.loader is not None
        t0 = time.monotonic()
        try:
            spec.loader.exec_module(mod)
            rc = mod.main()
        except Exception as e:  # report and go on with the others
            print(f"[bench] {f.stem} raised {e!r}", file=sys.stderr)
            rc = 1
        failed += bool(rc)
        print(f"[bench] {f.stem} done in {time.monotonic() - t0:.1f} s", flush=True)
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
