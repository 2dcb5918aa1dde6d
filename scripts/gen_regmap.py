#!/usr/bin/env python3
"""Generate the register-map views (Verilog include, C header, Python module,
Markdown data sheet) from rtl/soc/regmap.toml.  --check: write nothing, exit 1
if any generated file is stale."""

from __future__ import annotations

import argparse
import sys

from torqueloop import regmap
from torqueloop.hdl import REPO_ROOT


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--check", action="store_true", help="only compare, exit 1 if stale")
    args = ap.parse_args()
    stale = []
    for rel, text in regmap.generate().items():
        path = REPO_ROOT / rel
        if path.exists() and path.read_text() == text:
            continue
        stale.append(rel)
        if not args.check:
            path.parent.mkdir(parents=True, exist_ok=True)
            path.write_text(text)
            print(f"[gen_regmap] wrote {rel}")
    if args.check and stale:
        print("[gen_regmap] stale: " + ", ".join(stale) + " (run python scripts/gen_regmap.py)", file=sys.stderr)
        return 1
    if not stale:
        print("[gen_regmap] all generated files up to date")
    return 0


if __name__ == "__main__":
    sys.exit(main())
