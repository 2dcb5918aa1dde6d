#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Constraint consistency check of the DE0-CV Quartus project (no Quartus needed).

Every top-level port has a pin and an I/O standard, no pin is used twice,
every pin matches the board table, every source file of the SoC is in the
project, the .sdc names ports that exist, and the generated files are in
step with constraints/pins.toml.  Details: torqueloop/flow/constraints_check.py.
Exit status 1 if anything fails; every problem is listed.
"""

from __future__ import annotations

import sys
import time

from torqueloop.flow.constraints_check import run_all


def main() -> int:
    t0 = time.monotonic()
    checks = run_all()
    for c in checks:
        mark = "skip" if c.skipped else ("ok  " if c.ok else "FAIL")
        print(f"[constraints] {mark} {c.name}" + (f"  ({c.detail})" if c.skipped else ""))
    failed = [c for c in checks if not c.ok]
    for c in failed:
        lines = c.detail.splitlines()
        more = f"\n... and {len(lines) - 40} more" if len(lines) > 40 else ""
        print(f"\n---- {c.name} ----\n" + "\n".join(lines[:40]) + more + "\n", file=sys.stderr)
    print(f"[constraints] {len(checks) - len(failed)} passed, {len(failed)} failed "
          f"in {time.monotonic() - t0:.1f} s")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
