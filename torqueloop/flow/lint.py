# SPDX-License-Identifier: MIT
"""make lint's core checks (``python -m torqueloop.flow lint [CORE ...]``): Verilator -Wall, GHDL --std=08, Yosys synth -check and the
VHDL/Verilog equivalence proof for every core in rtl/manifest.toml.
Exit status 1 if anything fails; every problem is listed."""

from __future__ import annotations

import sys
import time
from concurrent.futures import ThreadPoolExecutor

from torqueloop.flow import eda
from torqueloop.flow.manifest import core_command_line


def main() -> int:
    args, cores = core_command_line(__doc__, "all")
    names = args.cores or list(cores)
    jobs = []
    for n in names:
        c = cores[n]
        if c.verilog:
            jobs.append(lambda c=c: eda.verilator_lint(c))
            if c.synth:
                jobs.append(lambda c=c: eda.yosys_check(c))
        if c.vhdl:
            jobs.append(lambda c=c: eda.ghdl_analyse(c))
        if c.equiv and c.vhdl and c.verilog:
            jobs.append(lambda c=c: eda.equivalence(c))
        if c.formal:
            jobs.append(lambda c=c: eda.prove_properties(c))
    t0 = time.monotonic()
    with ThreadPoolExecutor(max_workers=args.jobs) as pool:
        results = []
        for r in pool.map(lambda f: f(), jobs):
            results.extend(r if isinstance(r, list) else [r])
    failed = [r for r in results if not r.ok]
    for r in results:
        mark = "ok  " if r.ok else "FAIL"
        extra = f"  ({r.detail})" if r.ok and r.what.startswith(("equivalence", "formal")) else ""
        print(f"[lint] {mark} {r.what}{extra}")
    for r in failed:
        print(f"\n---- {r.what} ----\n{r.detail}\n", file=sys.stderr)
    print(f"[lint] {len(results) - len(failed)} passed, {len(failed)} failed in {time.monotonic() - t0:.1f} s")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
