"""freq_div + pwm_torque: frequency error of the integer divider (eq. 4) over
the paper's 50-500 Hz sweep and at 20 kHz, and the Cyclone V cost and logic
depth of both cores at the DE0-CV defaults (PWM_BITS = 10, DIV_BITS = 16)."""

from __future__ import annotations

import re
import subprocess

from torqueloop import eda
from torqueloop.hdl import core
from torqueloop.ref.freq_div import frequency_error

FREQS_HZ = [50, 100, 150, 200, 250, 300, 350, 400, 450, 500, 20_000]


def frequency_table() -> None:
    print("f_motor wanted | Count_max | f (eq. 2, x1024) | error | f on the pins (x1023) | error")
    for f in FREQS_HZ:
        e = frequency_error(f)
        print(f"{f:>10} Hz | {e.count_max:>9} | {e.f_eq2_hz:>12.2f} Hz | {100 * e.error_eq2:+6.2f} % "
              f"| {e.f_carrier_hz:>12.2f} Hz | {100 * e.error_carrier:+6.2f} %")


def logic_depth(name: str) -> int:
    """Cells on the longest register-to-register path (flip-flops cut out of the graph)."""
    c = core(name)
    files = " ".join(str(p) for p in c.verilog)
    script = (f"read_verilog -defer {files}\nhierarchy -check -top {c.top}\n"
              f"synth_intel_alm -family cyclonev -top {c.top} -noiopad\n"
              "ltp -noff * t:MISTRAL_FF %d\n")
    out = subprocess.run(["yosys", "-p", script], capture_output=True, text=True, check=True).stdout
    m = re.search(r"Longest topological path in \S+ \(length=(-?\d+)\)", out)
    return int(m.group(1)) if m else -1


def main() -> int:
    frequency_table()
    print()
    print("core       | LUTs | carry | FFs | DSP | longest path (cells, FFs cut)")
    bad = 0
    for name in ("freq_div", "pwm_torque"):
        r = eda.synth_cyclonev(core(name), tag="bench")
        if "error" in r:
            print(f"{name}: synthesis failed\n{r['error']}")
            bad += 1
            continue
        print(f"{name:<10} | {r['luts']:>4} | {r['carry_cells']:>5} | {r['ffs']:>3} | {r['dsp']:>3} | {logic_depth(name)}")
    return 1 if bad else 0


if __name__ == "__main__":
    raise SystemExit(main())
