# SPDX-License-Identifier: MIT
"""UART: divisor and rate error for the RN-XV's rates at 50 MHz, the
receiver's rate tolerance (reference decoder swept), Cyclone V resources per
FIFO depth, and how long the VHDL/Verilog equivalence proof takes per depth."""

from __future__ import annotations

import dataclasses
import random
import time

from torqueloop.flow import eda
from torqueloop.flow.manifest import core
from torqueloop.oracles.uart import LineDecoder, UartParams, baud_of, div_for, frame_segments


def tolerance(div: int, sign: int, rng: random.Random) -> float:
    """Largest rate error (in 0.1 % steps) at which 50 random bytes still decode."""
    data = bytes(rng.getrandbits(8) for _ in range(50))
    ok = 0.0
    for k in range(1, 200):
        e = sign * k * 1e-3
        segs = [(1, 3)]
        for b in data:
            segs += frame_segments(b, (div + 1) * (1 + e))
        ev = LineDecoder(div).decode(segs)
        if [(x.kind, x.data) for x in ev] != [("byte", b) for b in data]:
            break
        ok = e
    return ok


def main() -> int:
    p = UartParams()
    print("| baud | baud_div | actual | error |")
    print("|---:|---:|---:|---:|")
    for baud in (9600, 19200, 38400, 57600, 115200, 230400, 460800, 921600):
        d = div_for(baud, p.clk_hz)
        a = baud_of(d, p.clk_hz)
        print(f"| {baud} | {d}{' (0 = default)' if d == p.default_div else ''} | {a:,.0f} | {100 * (a / baud - 1):+.3f} % |")
    rng = random.Random(1)
    print("\nreceiver tolerance (sender rate error, back-to-back frames, reference decoder):")
    for div in (15, 63, 433):
        print(f"  {div + 1:4d} clocks/bit: sender slow {100 * tolerance(div, +1, rng):+.1f} % .. "
              f"fast {100 * tolerance(div, -1, rng):+.1f} %  (timing of the bits on the line)")
    print("\nCyclone V (yosys synth_intel_alm), uart top:")
    for depth in (16, 64):
        r = eda.synth_cyclonev(core("uart"), params={"FIFO_DEPTH": depth}, tag=f"bench_d{depth}")
        if "error" in r:
            print("synthesis failed:", r["error"])
            return 1
        print(f"  FIFO_DEPTH {depth:3d}: {r['luts']} LUTs, {r['carry_cells']} carry, {r['ffs']} FFs, "
              f"{r['mlab']} MLAB cells, {r['m10k']} M10K")
    print("\nequivalence proof (induction, FIFO words matched by name) vs FIFO depth:")
    c = core("sync_fifo")
    for depth in (16, 64, 128):
        t0 = time.monotonic()
        res = eda.equivalence(dataclasses.replace(c, synth_params={"DEPTH": depth}),
                              work=eda.BUILD / "bench" / f"fifo_equiv_{depth}")
        print(f"  sync_fifo DEPTH {depth:3d}: {'proven' if res.ok else 'FAILED'} in {time.monotonic() - t0:.1f} s")
        if not res.ok:
            return 1
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
