# SPDX-License-Identifier: MIT
"""Quadrature decoder: maximum count rate and glitch rejection per filter
setting (from the reference model's formulas, checked tight in
tests/test_oracle_quad_decoder.py), the default setting's margin over the
paper's motor, and Cyclone V resources."""

from __future__ import annotations

from torqueloop.flow import eda
from torqueloop.flow.manifest import core
from torqueloop.oracles.quad_decoder import (
    COUNTS_PER_MOTOR_REV,
    COUNTS_PER_SCREW_REV,
    QuadSettings,
    max_count_rate,
    max_rejected_glitch_clocks,
    min_accepted_pulse_clocks,
)
from torqueloop.spec.system import SYSTEM

CLK_HZ = float(SYSTEM.clk_hz)


def main() -> int:
    print(f"clock {CLK_HZ / 1e6:.0f} MHz; f_max = f_s * min(1, 2/N) for ideal quadrature, one direction\n")
    print("| sample_div | f_s | N | max count rate | motor rpm at f_max (64 cpr) | glitch always rejected | pulse always accepted |")
    print("|---:|---:|---:|---:|---:|---:|---:|")
    for div in (0, 4, 49, 499):
        for n in (1, 2, 4, 10, 15):
            s = QuadSettings(div, n)
            f = max_count_rate(CLK_HZ, s)
            rpm = f / COUNTS_PER_MOTOR_REV * 60
            rej = max_rejected_glitch_clocks(s) / CLK_HZ
            acc = min_accepted_pulse_clocks(s) / CLK_HZ
            mark = "  (reset default)" if s == QuadSettings() else ""
            print(f"| {div} | {CLK_HZ / (div + 1) / 1e3:.1f} kHz | {n} | {f / 1e3:.1f} kcounts/s | "
                  f"{rpm:,.0f} | <= {rej * 1e6:.2f} us | >= {acc * 1e6:.2f} us |{mark}")
    d = QuadSettings()
    motor = 10_000 / 60 * COUNTS_PER_MOTOR_REV
    print(f"\npaper motor at 10k rpm (upper end): {motor / 1e3:.1f} kcounts/s; default f_max "
          f"{max_count_rate(CLK_HZ, d) / 1e3:.0f} kcounts/s -> margin x{max_count_rate(CLK_HZ, d) / motor:.1f}")
    print(f"resolution: {COUNTS_PER_SCREW_REV} counts per ball-screw turn = "
          f"{4e-3 / COUNTS_PER_SCREW_REV * 1e9:.0f} nm per count (4 mm lead)")
    r = eda.synth_cyclonev(core("quad_decoder"))
    if "error" in r:
        print("synthesis failed:", r["error"])
        return 1
    print(f"\nCyclone V (yosys synth_intel_alm): {r['luts']} LUTs, {r['carry_cells']} carry cells, {r['ffs']} FFs")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
