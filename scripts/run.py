#!/usr/bin/env python3
"""make run: the project's main job.

Until the RTL-in-the-loop experiment exists, this runs the richest demo the
project has; each stage is skipped with a message if its code has not landed.
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def main() -> int:
    stages = [
        ("Cyclone V resource table", [sys.executable, str(ROOT / "scripts" / "synth.py")]),
    ]
    rc = 0
    for title, cmd in stages:
        print(f"\n[run] === {title} ===", flush=True)
        rc |= subprocess.call(cmd, cwd=ROOT)
    return rc


if __name__ == "__main__":
    sys.exit(main())
