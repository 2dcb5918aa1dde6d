# SPDX-License-Identifier: MIT
"""Every file generated from a single source, written or checked in one place.

    python -m torqueloop.flow.generate           # write the stale ones
    python -m torqueloop.flow.generate --check   # write nothing, exit 1 if any is stale
    python -m torqueloop.flow.generate --diff    # the same, with what writing would change

Sources and their views:

* ``torqueloop/spec/regmap.toml``   -> Verilog include, VHDL package, C header,
  docs/registers.md (:mod:`.gen_regmap`), the firmware linker script (:mod:`.gen_linker`)
* ``torqueloop/spec/protocol.toml`` -> C header, docs/protocol.md (:mod:`.gen_protocol`)
* ``constraints/pins.toml``         -> .qsf, .sdc, the board top's GPIO block, the cable
  harness of the board test wrappers (torqueloop/sim/harness/de0_cv_cable.v) and docs/hardware.md's wiring
  table (:mod:`.quartus`), the wiring diagram docs/wiring.svg (:mod:`.wiring`)

``make lint`` runs the check, so a stale generated file cannot land.
"""

from __future__ import annotations

import argparse
import difflib
import sys
from typing import Callable

from torqueloop.flow.licence import with_licence
from torqueloop.spec.repo import REPO_ROOT


def products() -> dict[str, str]:
    """Every generated file (path from the repo root) with the text it should have."""
    from torqueloop.flow import gen_linker, gen_protocol, gen_regmap, quartus, wiring

    out: dict[str, str] = {}
    out.update(gen_regmap.generate())
    out.update({path: fn() for path, fn in gen_linker.OUTPUTS.items()})
    out.update({path: fn() for path, fn in gen_protocol.OUTPUTS.items()})
    out.update({str(p.path.relative_to(REPO_ROOT)): p.text for p in quartus.products()})
    out.update({path: fn() for path, fn in wiring.OUTPUTS.items()})
    return {rel: with_licence(rel, text) for rel, text in out.items()}


def stale(prods: dict[str, str]) -> list[str]:
    """The generated files whose committed text differs from what the generator makes now."""
    return [rel for rel, text in prods.items()
            if not (REPO_ROOT / rel).exists() or (REPO_ROOT / rel).read_text() != text]


def diff(rel: str, text: str) -> str:
    """What writing ``text`` would change in ``rel`` (a unified diff)."""
    path = REPO_ROOT / rel
    old = path.read_text() if path.exists() else ""
    return "".join(difflib.unified_diff(old.splitlines(True), text.splitlines(True), f"a/{rel}", f"b/{rel}"))


def main(argv: list[str] | None = None, log: Callable[[str], None] = print) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    g = ap.add_mutually_exclusive_group()
    g.add_argument("--check", action="store_true", help="only compare; exit 1 if a generated file is stale")
    g.add_argument("--diff", action="store_true", help="like --check, and show what writing would change")
    args = ap.parse_args(argv)
    prods = products()
    bad = stale(prods)
    if args.check or args.diff:
        for rel in bad:
            log(f"[generate] stale: {rel} (run: python -m torqueloop.flow.generate)")
            if args.diff:
                log(diff(rel, prods[rel]))
        if not bad:
            log(f"[generate] {len(prods)} generated files up to date")
        return 1 if bad else 0
    for rel in bad:
        path = REPO_ROOT / rel
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(prods[rel])
        log(f"[generate] wrote {rel}")
    if not bad:
        log(f"[generate] {len(prods)} generated files up to date")
    return 0


if __name__ == "__main__":
    sys.exit(main())
