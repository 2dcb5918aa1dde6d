# SPDX-License-Identifier: MIT
"""pwm_torque: the VHDL/Verilog equivalence proof at the default PWM_BITS = 10.

make lint proves the twins equivalent at PWM_BITS = 6 (core pwm_torque_equiv,
about 1.5 s); at 10 bits the 10x10 multiplier makes Yosys equiv_induct take
185 CPU-s on an idle machine (proven, 203 of 203 $equiv cells), so the
full-width proof lives here."""

from __future__ import annotations

import time
from dataclasses import replace

from torqueloop.flow import eda
from torqueloop.flow.manifest import core


def main() -> int:
    from bench import QUICK

    if QUICK:
        print("skipped in quick mode (about 3 CPU-minutes; make lint proves the 6-bit twins)")
        return 0
    c = replace(core("pwm_torque"), name="pwm_torque_w10", synth_params={"PWM_BITS": 10})
    print("proving pwm_torque.vhd == pwm_torque.v at PWM_BITS = 10 (3+ CPU-minutes) ...", flush=True)
    t0 = time.monotonic()
    r = eda.equivalence(c)
    print(f"{'PROVEN' if r.ok else 'FAILED'} in {time.monotonic() - t0:.1f} s: {r.detail[-600:]}")
    return 0 if r.ok else 1


if __name__ == "__main__":
    raise SystemExit(main())
