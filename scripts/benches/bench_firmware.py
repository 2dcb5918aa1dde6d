# SPDX-License-Identifier: MIT
"""Servo firmware figures: image size; the worst two-axis control iteration
(mcycle) and interrupt lateness at 20 kHz on the simulated SoC under
worst-case load, with step and with trapezoid moves, on both CPU cores (the
pipelined tl_cpu_pipe, the board's, and the multi-cycle tl_cpu), each named
explicitly so that the comparison does not depend on tl_soc's default; the
loop at 20 kHz for 2 s on the board image with the plant on the pins and
the link at 921 600 baud (torqueloop.sim.experiment.run_fast_loop); and a
long libFuzzer run of the receive path."""

from __future__ import annotations

import json
import os
import sys
import time

from torqueloop.flow.firmware import build
from torqueloop.flow.simrun import run
from torqueloop.flow.tb_images import servo_tb_image
from torqueloop.spec.regs import CLK_HZ
from torqueloop.spec.repo import REPO_ROOT as REPO

FUZZ_SECONDS = int(os.environ.get("TL_FUZZ_BENCH_SECONDS", "120"))


#: 25 us: 20 kHz at 50 % of the CPU (the control budget)
BUDGET_CYCLES = 1250
#: the worst iteration the pipelined core is to reach (docs/cpu.md, Status)
PIPE_ITERATION_TARGET = 900
#: the cores: name (as scripts/run_elf.py --core calls them) -> tl_soc's CPU_PIPELINED
CORES = {"pipe": 1, "multi": 0}


def _measure(period_us: int, move_mode: int = 1, short: bool = False, *, cpu_pipelined: int,
             kvff_q16: int = 0, kaff_q16: int = 0) -> dict:
    """The firmware test bench's worst-case measurement on the SoC with the core
    ``cpu_pipelined`` names (tl_soc's CPU_PIPELINED, always passed: 1 the
    pipelined core, 0 the multi-cycle one), with the velocity and acceleration
    feed-forwards off (0) or at these gains."""
    img = servo_tb_image()
    out = REPO / "build" / "firmware" / (f"measure_{period_us}_{move_mode}{'_short' if short else ''}"
                                         f"{'_pipe' if cpu_pipelined else '_multi'}"
                                         f"{f'_ff{kvff_q16}_{kaff_q16}' if kvff_q16 or kaff_q16 else ''}.json")
    run("soc", "verilator", "test_firmware", bench="firmware",
        parameters={"RAM_INIT": f'"{img.ram_hex}"', "ROM_INIT": f'"{img.rom_hex}"',
                    "CPU_PIPELINED": cpu_pipelined},
        testcase="measure_control_iteration",
        extra_env={"TL_FW_MEASURE": "1", "TL_FW_PERIOD_US": str(period_us), "TL_FW_MOVE_MODE": str(move_mode),
                   "TL_FW_SHORT_MOVE": "1" if short else "0", "TL_FW_MEASURE_OUT": str(out),
                   "TL_FW_KVFF_Q16": str(kvff_q16), "TL_FW_KAFF_Q16": str(kaff_q16)})
    return json.loads(out.read_text())


def main() -> int:
    img = build("servo")
    print(f"image: text+rodata {img.text_bytes} B, data {img.data_bytes} B, bss {img.bss_bytes} B "
          f"(RAM 65536 B, 4096 B stack)")
    for period, mode, short, what in ((50, 0, False, "step moves"), (50, 1, False, "trapezoid moves (accelerating)"),
                                      (50, 1, True, "trapezoid moves (60 counts: accelerating, cruising, braking)")):
        for name, pipelined in CORES.items():
            t0 = time.monotonic()
            try:
                m = _measure(period, mode, short, cpu_pipelined=pipelined)
            except Exception as e:   # report and go on with the rest
                print(f"{name:5s} control iteration at {period} us, {what}: failed: {e!r}")
                continue
            cyc, late = m["loop_cycles_max"], m["jitter_cycles_max"]
            target = f"; target {PIPE_ITERATION_TARGET}" if pipelined else ""
            print(f"{name:5s} control iteration at {1e3 / period:.0f} kHz, both axes PID, edge-timestamp velocity, "
                  f"{what}, encoders counting, telemetry streaming, link traffic: worst {cyc} cycles = "
                  f"{cyc / CLK_HZ * 1e6:.1f} us ({cyc / BUDGET_CYCLES * 100:.0f} % of the {BUDGET_CYCLES}-cycle budget "
                  f"of a 20 kHz loop, {cyc / (50e-6 * CLK_HZ) * 100:.0f} % of a 50 us period{target}); worst "
                  f"interrupt lateness {late} cycles = {late / CLK_HZ * 1e6:.2f} us  ({time.monotonic() - t0:.0f} s)")
            print(f"      {m['commands_answered']} commands answered in 3 ms, telemetry {m['telemetry_frames']} frames "
                  f"sent / {m['telemetry_dropped']} dropped (1 Mbaud), faults {m['faults']}")
    from torqueloop.sim.experiment import run_fast_loop
    from bench import QUICK as quick   # scripts/bench.py's flag (make bench QUICK=1)
    # Table 1's gains and the plant on the pins reach paths the bench's cases do not (sparse counts
    # meeting the runaway checks in full, the braking plan): 2 s holds a screw turn's whole trapezoid
    # at the default VMAX/AMAX (1.5 s), its braking plan and landing included
    for mode, what in ((0, "steps"), (1, "trapezoids")):
        r = run_fast_loop(seconds=0.05 if quick else 2.0, move_mode=mode)
        print(f"board image at 20 kHz for {r.seconds:g} s, both axes PID (Table 1's gains), one-turn {what} "
              f"({r.moved_counts} counts), plant on the pins, link {r.baud:.0f} baud, telemetry every "
              f"{r.telemetry_every} periods: worst iteration {r.loop_cycles_max} cycles (target "
              f"{PIPE_ITERATION_TARGET}), worst interrupt lateness {r.jitter_cycles_max} cycles = "
              f"{r.jitter_cycles_max / CLK_HZ * 1e6:.1f} us; {r.frames} of {r.frames_expected} telemetry frames, "
              f"{r.frames_missing} missing, {r.tx_dropped} dropped, faults {r.faults}  ({r.cpu_s:.0f} CPU-s)")
    from torqueloop.flow.firmware import run_fuzz
    seconds = 5 if quick else FUZZ_SECONDS
    runs, _ = run_fuzz(seconds)
    print(f"fuzz: {runs} inputs in {seconds} s, no crash, no sanitizer report, no state change from noise")
    return 0


if __name__ == "__main__":
    sys.exit(main())
