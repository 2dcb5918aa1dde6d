# SPDX-License-Identifier: MIT
"""freq_div + pwm_torque: frequency error of the integer divider (eq. 4) over
the paper's 50-500 Hz sweep and at 20 kHz, and the Cyclone V cost and logic
depth of both cores at the DE0-CV defaults (PWM_BITS = 10, DIV_BITS = 16)."""

from __future__ import annotations

from torqueloop.flow import eda
from torqueloop.flow.manifest import core
from torqueloop.oracles.freq_div import frequency_error

FREQS_HZ = [50, 100, 150, 200, 250, 300, 350, 400, 450, 500, 20_000]


def frequency_table() -> None:
    print("f_motor wanted | Count_max | f (eq. 2, x1024) | error | f on the pins (x1023) | error")
    for f in FREQS_HZ:
        e = frequency_error(f)
        print(f"{f:>10} Hz | {e.count_max:>9} | {e.f_eq2_hz:>12.2f} Hz | {100 * e.error_eq2:+6.2f} % "
              f"| {e.f_carrier_hz:>12.2f} Hz | {100 * e.error_carrier:+6.2f} %")


def main() -> int:
    frequency_table()
    print()
    print("core       | LUTs | carry | FFs | DSP | LUT levels | ltp cells (carry hops counted)")
    bad = 0
    for name in ("freq_div", "pwm_torque"):
        r = eda.synth_cyclonev(core(name), tag="bench")
        if "error" in r:
            print(f"{name}: synthesis failed\n{r['error']}")
            bad += 1
            continue
        print(f"{name:<10} | {r['luts']:>4} | {r['carry_cells']:>5} | {r['ffs']:>3} | {r['dsp']:>3} "
              f"| {r['lut_levels']:>10} | {r['longest_path_cells']}")
    return 1 if bad else 0


if __name__ == "__main__":
    raise SystemExit(main())
