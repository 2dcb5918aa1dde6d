#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""make synth: Yosys synth_intel_alm -family cyclonev on every synthesisable
core of rtl/manifest.toml; writes build/synth/resources.{md,json} and prints
the table."""

from __future__ import annotations

import sys
from concurrent.futures import ThreadPoolExecutor

from torqueloop.flow import eda
from torqueloop.flow.manifest import core_command_line


def main() -> int:
    args, cores = core_command_line(__doc__, "all with synth = true")
    chosen = [cores[n] for n in args.cores] if args.cores else [c for c in cores.values() if c.synth]
    with ThreadPoolExecutor(max_workers=args.jobs) as pool:
        rows = list(pool.map(eda.synth_cyclonev, chosen))
    md = eda.write_synth_table(rows)
    print(md.read_text())
    print(f"[synth] table written to {md.relative_to(eda.REPO_ROOT)} (and resources.json)")
    bad = [r["core"] for r in rows if "error" in r]
    for r in rows:
        if "error" in r:
            print(f"[synth] {r['core']} failed:\n{r['error']}", file=sys.stderr)
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
