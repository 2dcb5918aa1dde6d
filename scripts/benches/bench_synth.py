# SPDX-License-Identifier: MIT
"""Cyclone V resources of every synthesisable core (Yosys synth_intel_alm)."""

from torqueloop.flow import eda
from torqueloop.flow.manifest import load_manifest


def main() -> int:
    rows = [eda.synth_cyclonev(c) for c in load_manifest().values() if c.synth]
    print(eda.write_synth_table(rows).read_text())
    return 1 if any("error" in r for r in rows) else 0
