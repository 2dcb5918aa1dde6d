# SPDX-License-Identifier: MIT
"""Every file generated from a single source, written or checked in one place.

    python -m torqueloop.flow.generate           # write the stale ones
    python -m torqueloop.flow.generate --check   # write nothing, exit 1 if any is stale

Sources and their views:

* ``torqueloop/spec/regmap.toml``   -> Verilog include, VHDL package, C header,
  docs/registers.md (:mod:`.gen_regmap`), the firmware linker script (:mod:`.gen_linker`)
* ``torqueloop/spec/protocol.toml`` -> C header, docs/protocol.md (:mod:`.gen_protocol`)
* ``constraints/pins.toml``         -> .qsf, .sdc, the board top's GPIO block, the cable
  harness of the board test wrappers (tb/de0_cv_top/de0_cv_cable.v) and docs/hardware.md's wiring
  table (:mod:`.quartus`), the wiring diagram docs/wiring.svg (:mod:`.wiring`)

``make lint`` runs the check, so a stale generated file cannot land.
"""

from __future__ import annotations

import argparse
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
    return [rel for rel, text in prods.items()
            if not (REPO_ROOT / rel).exists() or (REPO_ROOT / rel).read_text() != text]


def main(argv: list[str] | None = None, log: Callable[[str], None] = print) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--check", action="store_true", help="only compare; exit 1 if a generated file is stale")
    args = ap.parse_args(argv)
    prods = products()
    bad = stale(prods)
    if args.check:
        for rel in bad:
            log(f"[generate] stale: {rel} (run: python -m torqueloop.flow.generate)")
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
