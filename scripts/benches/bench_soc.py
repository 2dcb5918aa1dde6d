# SPDX-License-Identifier: MIT
"""Cyclone V resources of the SoC at full size (Yosys synth_intel_alm):
the fabric (everything but the CPU) and the whole SoC, both with the
default 64 KiB RAM, against the 5CEBA4's budget.  make lint/synth use a
1 KiB RAM (generic synthesis maps memories to flops); this is the figure
that says whether the RAM lands in M10K blocks and fits."""

from __future__ import annotations

import time

from torqueloop.flow import eda
from torqueloop.flow.manifest import load_manifest
from torqueloop.flow.gen_regmap import load

# 5CEBA4F23C7 (Cyclone V E A4): Intel's device table.
DEVICE_ALMS = 18_480
DEVICE_M10K = 308


def main() -> int:
    cores = load_manifest()
    ram = load().region("RAM").size
    rows = []
    for name in ("soc_fabric", "soc"):
        t0 = time.monotonic()
        row = eda.synth_cyclonev(cores[name], params={"RAM_BYTES": ram}, tag="64k")
        row["seconds"] = round(time.monotonic() - t0, 1)
        rows.append(row)
        if "error" in row:
            print(f"{name}: synthesis failed\n{row['error']}")
            return 1
        print(f"{name} (RAM {ram // 1024} KiB): {row['luts']} LUTs, {row['carry_cells']} carry, "
              f"{row['ffs']} FFs, {row['m10k']} M10K of {DEVICE_M10K}, {row['mlab']} MLAB, "
              f"{row['dsp']} DSP, {row.get('lut_levels', '?')} LUT levels "
              f"(synthesis {row['seconds']} s)")
    print(eda.write_synth_table(rows, out_dir=eda.BUILD / "synth" / "soc_64k").read_text())
    soc = rows[-1]
    # ALMs hold up to two LUTs; a rough upper bound for the LUT share of the device.
    print(f"LUTs / (2 x ALMs) = {soc['luts'] / (2 * DEVICE_ALMS):.1%} of the 5CEBA4; "
          f"M10K {soc['m10k']}/{DEVICE_M10K} = {soc['m10k'] / DEVICE_M10K:.0%}")
    return 0 if soc["m10k"] <= DEVICE_M10K // 2 else 1
