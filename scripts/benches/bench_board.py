# SPDX-License-Identifier: MIT
"""Cyclone V resources of the whole board top (SoC + board logic) against the
DE0-CV's 5CEBA4: Yosys synth_intel_alm, with sanity bounds asserted.

ALMs are estimated from Yosys's cells, since Yosys does not pack ALMs (a
Cyclone V ALM holds one 6-input LUT or two smaller ones sharing its 8
inputs, two adder bits and four flip-flops): the packed estimate puts each
6-input LUT in its own ALM and two smaller LUTs or two carry cells in one
(and at least one ALM per four flip-flops); the upper bound gives every LUT
its own ALM.  The 20 % bound applies to the
packed estimate.
M10K blocks are Yosys's mapping (it maps a 32-bit true dual-port RAM as
two blocks per 512 words; Quartus would use about half as many).
"""

from __future__ import annotations

import math
import time

from torqueloop.flow import eda
from torqueloop.flow.board_files import load_pin_table
from torqueloop.flow.manifest import load_manifest

#: 5CEBA4F23C7 (Cyclone V E A4)
DEVICE_ALMS = 18_480
DEVICE_M10K = 308
#: Logic must stay under a fifth of the device: the paper's system is small,
#: and the rest is headroom for Signal Tap and future axes.
ALM_BOUND = 0.20
#: 64 KiB of program RAM is a design choice (about a fifth of the blocks in
#: Quartus); Yosys's mapping doubles it, hence the looser bound.
M10K_BOUND = 0.50
#: Longest register-to-register path in LUT levels; well above this, 50 MHz
#: (20 ns, roughly 0.5-1 ns per level plus routing) is at risk.
DEPTH_BOUND = 20


def alm_estimate(row: dict) -> tuple[int, int]:
    """(packed, upper): packed = a 6-input LUT per ALM, two smaller LUTs or
    two carry cells per ALM; upper = one ALM per LUT."""
    cells = row["cells"]
    lut6 = cells.get("MISTRAL_ALUT6", 0)
    packed = lut6 + math.ceil((row["luts"] - lut6) / 2) + math.ceil(row["carry_cells"] / 2)
    upper = row["luts"] + math.ceil(row["carry_cells"] / 2)
    # An ALM holds four flip-flops: a register-heavy design needs at least that many.
    floor = math.ceil(row["ffs"] / 4)
    return max(packed, floor), max(upper, floor)


def main() -> int:
    top = load_pin_table().board.top
    cores = load_manifest()
    if top not in cores:
        print(f"[bench_board] core {top} not in rtl/manifest.toml yet (waits for rtl/soc/tl_soc.v)")
        return 1
    t0 = time.monotonic()
    print(f"[bench_board] synthesising {top} (full-size RAM) with synth_intel_alm, about a minute ...", flush=True)
    row = eda.synth_cyclonev(cores[top], tag="board")
    if "error" in row:
        print(f"[bench_board] synthesis failed:\n{row['error']}")
        return 1
    lo, hi = alm_estimate(row)
    depth = row["lut_levels"]
    print(f"board top {top}: Yosys synth_intel_alm -family cyclonev in {time.monotonic() - t0:.0f} s")
    print("packing rule: one ALM per 6-input LUT, per two smaller LUTs, per two carry cells, at least one per four FFs")
    print("| resource | used | device | share |")
    print("|---|---:|---:|---:|")
    print(f"| ALMs (packed estimate) | {lo} | {DEVICE_ALMS} | {lo / DEVICE_ALMS:.1%} |")
    print(f"| ALMs (one per LUT, upper bound) | {hi} | {DEVICE_ALMS} | {hi / DEVICE_ALMS:.1%} |")
    print(f"| LUTs | {row['luts']} | | |")
    print(f"| carry cells | {row['carry_cells']} | | |")
    print(f"| flip-flops | {row['ffs']} | {4 * DEVICE_ALMS} | {row['ffs'] / (4 * DEVICE_ALMS):.1%} |")
    print(f"| M10K | {row['m10k']} | {DEVICE_M10K} | {row['m10k'] / DEVICE_M10K:.1%} |")
    print(f"| MLAB | {row['mlab']} | | |")
    print(f"| DSP | {row['dsp']} | 66 | {row['dsp'] / 66:.1%} |")
    print(f"| logic depth (LUT levels, eda.lut_levels) | {depth} | bound {DEPTH_BOUND} | |")
    bad = []
    if lo > ALM_BOUND * DEVICE_ALMS:
        bad.append(f"ALM estimate {lo} above {ALM_BOUND:.0%} of the device")
    if row["m10k"] > M10K_BOUND * DEVICE_M10K:
        bad.append(f"{row['m10k']} M10K above {M10K_BOUND:.0%} of the device")
    if depth > DEPTH_BOUND:
        bad.append(f"logic depth {depth} above {DEPTH_BOUND}")
    for b in bad:
        print(f"[bench_board] FAIL {b}")
    return 1 if bad else 0
