# SPDX-License-Identifier: MIT
"""Servo firmware figures: image size, worst cycles per control iteration and
interrupt lateness at the fastest period on the simulated SoC (Verilator,
worst-case load), and a long libFuzzer run of the receive path."""

from __future__ import annotations

import json
import os
import sys
import time

from torqueloop.flow.firmware import build
from torqueloop.flow.simrun import run
from torqueloop.spec.regs import CLK_HZ
from torqueloop.spec.repo import REPO_ROOT as REPO

FUZZ_SECONDS = int(os.environ.get("TL_FUZZ_BENCH_SECONDS", "120"))


def _measure(period_us: int) -> dict:
    from bench import tb_module
    T = tb_module("firmware", "test_firmware")
    img = build("servo_tb", {k: str(v) for k, v in T.DEFINES.items()})
    out = REPO / "build" / "firmware" / f"measure_{period_us}.json"
    run("soc", "verilator", "test_firmware",
        parameters={"RAM_INIT": f'"{img.ram_hex}"', "ROM_INIT": f'"{img.rom_hex}"'},
        testcase="measure_control_iteration",
        extra_env={"TL_FW_MEASURE": "1", "TL_FW_PERIOD_US": str(period_us), "TL_FW_MEASURE_OUT": str(out)})
    return json.loads(out.read_text())


def main() -> int:
    img = build("servo")
    print(f"image: text+rodata {img.text_bytes} B, data {img.data_bytes} B, bss {img.bss_bytes} B "
          f"(RAM 65536 B, 4096 B stack)")
    t0 = time.monotonic()
    m = _measure(200)
    cyc, late = m["loop_cycles_max"], m["jitter_cycles_max"]
    print(f"control iteration, both axes PID + trapezoid, encoders counting, telemetry streaming: "
          f"worst {cyc} cycles = {cyc / CLK_HZ * 1e6:.1f} us; worst interrupt lateness {late} cycles "
          f"= {late / CLK_HZ * 1e6:.2f} us  ({time.monotonic() - t0:.0f} s)")
    print(f"  at PERIOD_US 200 (5 kHz): control load {cyc / (200e-6 * CLK_HZ) * 100:.0f} % of the CPU, "
          f"{m['commands_answered']} commands answered in 3 ms, telemetry {m['telemetry_frames']} frames "
          f"sent / {m['telemetry_dropped']} dropped (1 Mbaud link), faults {m['faults']}")
    print(f"  at the paper's 25 ms: control load {cyc / (25e-3 * CLK_HZ) * 100:.2f} %")
    from torqueloop.flow.firmware import run_fuzz
    runs, _ = run_fuzz(FUZZ_SECONDS)
    print(f"fuzz: {runs} inputs in {FUZZ_SECONDS} s, no crash, no sanitizer report, no state change from noise")
    return 0


if __name__ == "__main__":
    sys.exit(main())
