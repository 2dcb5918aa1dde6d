#!/usr/bin/env python3
"""Generate the C header and docs/protocol.md from firmware/protocol/protocol.toml.

    python scripts/gen_protocol.py          # write the generated files
    python scripts/gen_protocol.py --check  # exit 1 if any is stale

torqueloop/protocol.py reads the TOML itself (no generated Python to go stale).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(REPO))

from torqueloop import protocol  # noqa: E402

OUTPUTS = {
    REPO / "firmware" / "protocol" / "tl_protocol.h": protocol.c_header,
    REPO / "docs" / "protocol.md": protocol.markdown,
}


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--check", action="store_true")
    args = ap.parse_args(argv)
    stale = []
    for path, gen in OUTPUTS.items():
        text = gen()
        if args.check:
            if not path.exists() or path.read_text() != text:
                stale.append(path)
        else:
            path.write_text(text)
            print(f"wrote {path.relative_to(REPO)}")
    for p in stale:
        print(f"stale: {p.relative_to(REPO)} (run python scripts/gen_protocol.py)")
    return 1 if stale else 0


if __name__ == "__main__":
    sys.exit(main())
