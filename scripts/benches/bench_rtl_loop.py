# SPDX-License-Identifier: MIT
"""RTL in the loop: simulated clock cycles per CPU second of the native
harness build against the portable baseline build (torqueloop.sim.native:
DEFAULT against BASELINE), measured side by side in this run - the board
image alone and the full closed loop (servo firmware on the board image, two
axes, plant on the pins, host link) - with the telemetry of the two builds
compared; what each harness idea gains on its own (board alone, CPU time and,
where valgrind is installed, instructions per clock); the projected CPU time
of the paper's 40 s experiment; and the check that the cocotb and native
harnesses give the same telemetry.

The machine is shared: the builds are run alternately and the medians
compared, and instruction counts (callgrind) are the figure that the load
does not move."""

from __future__ import annotations

import dataclasses
import os
import re
import resource
import shutil
import statistics
import subprocess
from pathlib import Path

import numpy as np

from torqueloop.sim import cocotb_run, experiment, native
from torqueloop.spec.system import SYSTEM

CLK = SYSTEM.clk_hz
DRIVER_SRC = Path(__file__).resolve().with_name("board_alone.cpp")
DRIVER = native.BUILD / "board_alone"
#: BASELINE without -march=native, so valgrind (which lacks AVX-512) can run
#: it: the start of the per-idea ladder.
BASELINE_PORTABLE = dataclasses.replace(native.BASELINE, name="baseline-portable", opt_fast="-O3",
                                        opt_global="-O2")
#: The harness ideas one at a time, each on top of the previous one.
LADDER = [
    ("portable baseline, without -march=native", BASELINE_PORTABLE),
    ("+ one evaluation per clock", dataclasses.replace(BASELINE_PORTABLE, name="idea-1eval", eval_per_clock=1)),
    ("+ -O3 really (no -CFLAGS -O2 after it), harness -O3",
     dataclasses.replace(BASELINE_PORTABLE, name="idea-O3", eval_per_clock=1, cflags="-fPIC", harness_opt="-O3")),
    ("+ generated evaluation called directly",
     dataclasses.replace(native.DEFAULT, name="idea-direct", cxx="g++", skip_ico=False)),
    ("+ input phase skipped when no input changed", dataclasses.replace(native.DEFAULT, name="idea-ico", cxx="g++")),
    (f"+ {native.DEFAULT.cxx} (= DEFAULT)", native.DEFAULT),
]


def _driver() -> Path:
    if not DRIVER.exists() or DRIVER.stat().st_mtime < DRIVER_SRC.stat().st_mtime:
        DRIVER.parent.mkdir(parents=True, exist_ok=True)
        tmp = DRIVER.with_name(f"board_alone.{os.getpid()}")
        subprocess.run(["g++", "-O2", "-o", str(tmp), str(DRIVER_SRC), "-ldl"], check=True)
        os.replace(tmp, DRIVER)
    return DRIVER


def _alone(v: native.HarnessBuild, clocks: int) -> float:
    """Clocks per CPU second of the board image alone (firmware idle loop)."""
    out = subprocess.run([str(_driver()), str(native.build(harness=v)), str(clocks)],
                         capture_output=True, text=True, check=True)
    return float(out.stdout)


def _ir_per_clock(v: native.HarnessBuild, clocks: int) -> float | None:
    """Instructions per clock of the board alone (callgrind: two lengths, the
    difference), or None without valgrind."""
    if shutil.which("valgrind") is None:
        return None
    lib = str(native.build(harness=v))
    ir = []
    for n in (clocks, 2 * clocks):
        r = subprocess.run(["valgrind", "--tool=callgrind", "--callgrind-out-file=/dev/null",
                            str(_driver()), lib, str(n)], capture_output=True, text=True)
        m = re.search(r"Collected : (\d+)", r.stderr)
        if r.returncode or not m:
            return None
        ir.append(int(m.group(1)))
    return (ir[1] - ir[0]) / clocks


def _closed(v: native.HarnessBuild, t_end_s: float) -> experiment.RtlRun:
    cfg = experiment.ExperimentConfig(law="P", t_end_s=t_end_s, progress=False)
    return experiment.run_rtl(cfg, board_factory=lambda rom, ram: native.NativeBoard.create(rom, ram, harness=v))


def _line(name: str, r: experiment.RtlRun) -> None:
    b = r.bridge
    print(f"  {name:<22} {r.cycles:>12,} clocks  wall {r.wall_s:7.1f} s  CPU {r.cpu_s:7.1f} s  "
          f"{r.cycles / r.wall_s / 1e6:6.2f} Mclk/wall-s  {r.cycles / r.cpu_s / 1e6:6.2f} Mclk/CPU-s")
    if b.get("board_s"):
        rest = r.wall_s - b["board_s"] - b["plant_s"]
        print(f"  {'':<22} time in board {b['board_s']:.1f} s, plant {b['plant_s']:.1f} s, "
              f"link/recording {rest:.1f} s; {b['segments']} plant segments, {b['rollbacks']} rollbacks, "
              f"{b['edges']} encoder edges, {b['pin_changes']} pin changes")


def _same_telemetry(a: experiment.RtlRun, b: experiment.RtlRun) -> bool:
    n = min(len(a.traj.t), len(b.traj.t))
    return n > 0 and all(np.array_equal(getattr(a.traj, k)[:n], getattr(b.traj, k)[:n])
                         for k in ("pos", "vel", "cmd", "err"))


def main() -> int:
    from bench import QUICK as quick   # scripts/bench.py's flag (make bench QUICK=1)
    print(f"load average {os.getloadavg()[0]:.1f} on {os.cpu_count()} CPUs")
    img = experiment.firmware_image()
    native.install_images(img.rom_hex, img.ram_hex)
    for v in (native.DEFAULT, native.BASELINE):
        native.build(harness=v)

    # ---- board alone, the two builds alternately ------------------------------------------
    n_alone, reps = (2_000_000, 2) if quick else (4_000_000, 5)
    alone: dict[str, list[float]] = {"new": [], "old": []}
    for _ in range(reps):
        alone["old"].append(_alone(native.BASELINE, n_alone))
        alone["new"].append(_alone(native.DEFAULT, n_alone))
    new_a, old_a = statistics.median(alone["new"]), statistics.median(alone["old"])
    print(f"board image alone (firmware idle loop, no plant, no Python), median of {reps} alternate runs:")
    print(f"  portable baseline {old_a / 1e6:5.2f} Mclk/CPU-s, now {new_a / 1e6:5.2f} Mclk/CPU-s: "
          f"x{new_a / old_a:.2f}")

    # ---- the closed loop, the two builds alternately ----------------------------------------
    t_end, reps = (0.3, 1) if quick else (1.0, 2)
    runs: dict[str, list[experiment.RtlRun]] = {"new": [], "old": []}
    for _ in range(reps):
        runs["old"].append(_closed(native.BASELINE, t_end))
        runs["new"].append(_closed(native.DEFAULT, t_end))
    speed = {k: statistics.median(r.cycles / r.cpu_s for r in rs) for k, rs in runs.items()}
    print(f"closed loop (P, {t_end:g} s after the step, 25 ms period), median of {reps} alternate runs:")
    _line("before the speed work", runs["old"][-1])
    _line("now", runs["new"][-1])
    ratio = speed["new"] / speed["old"]
    same = all(_same_telemetry(r, runs["old"][0]) for r in runs["new"] + runs["old"][1:])
    print(f"  closed-loop clocks per CPU-second: {speed['old'] / 1e6:.2f} -> {speed['new'] / 1e6:.2f} M, "
          f"x{ratio:.2f} against the portable baseline build (target x2)")
    print(f"  telemetry of {len(runs['new'][0].traj.t)} control samples identical between the builds: {same}")
    cpu40 = 40 * CLK / speed["new"]
    print(f"  projected 40 s experiment: {cpu40:.0f} CPU-s per law ({cpu40 / 60:.1f} min; portable baseline "
          f"{40 * CLK / speed['old'] / 60:.1f} min); three laws on two free cores {1.5 * cpu40 / 60:.1f} min")
    print(f"  peak resident memory of this process: {resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024:.0f} MB")

    # ---- each idea on its own (board alone) ---------------------------------------------------
    if not quick:
        print("each harness idea on top of the previous ones, board alone "
              "(CPU time: median of 3; instructions per clock: callgrind):")
        prev_t = prev_ir = None
        for name, v in LADDER:
            t = statistics.median(_alone(v, 3_000_000) for _ in range(3))
            ir = _ir_per_clock(v, 300_000)
            gain_t = f"x{t / prev_t:.2f}" if prev_t else ""
            gain_ir = f"x{prev_ir / ir:.2f}" if prev_ir and ir else ""
            irs = f"{ir:6.0f} Ir/clk {gain_ir:>6}" if ir else "(no valgrind)"
            print(f"  {name:<58} {t / 1e6:5.2f} Mclk/CPU-s {gain_t:>6}   {irs}")
            prev_t, prev_ir = t, ir

    rep = Path(__file__).resolve().parents[2] / "build" / "report" / "report.json"
    if rep.exists():
        import json
        d = json.loads(rep.read_text())
        for law, v in d.get("arms", {}).get("experiment", {}).items():
            rr = v.get("run") or {}
            if "wall_s" in rr and "cycles_per_cpu_s" in rr:
                print(f"  last make run ({d['meta']['T_s']:.0f} s, {law}, experiment arm): {rr['wall_s']:.0f} s wall, "
                      f"{rr['cycles_per_cpu_s'] / 1e6:.2f} Mclk/CPU-s")

    # ---- cocotb harness against native on the same short run (fast link, 1 ms period) ---------
    short = experiment.ExperimentConfig(law="PD", t_end_s=0.02, period_us=1000, baud_div=15, progress=False)
    ref = experiment.run_rtl(short)
    _line("native, short PD", ref)
    # Icarus: the board's power-up, session and configuration alone are about 5.5 M clocks
    # (the native run above counts them), which Icarus simulates at about 1 k clocks per second (measured):
    # more than an hour, so only on request.
    icarus = os.environ.get("TL_BENCH_ICARUS") == "1" and not quick
    sims = ("verilator", "icarus") if icarus else ("verilator",)
    if not icarus:
        print(f"  cocotb icarus: not run ({ref.cycles / 1e6:.1f} M clocks at about 1 k clocks/s would take over an hour; "
              f"TL_BENCH_ICARUS=1 runs it)")
    for sim in sims:
        run_cfg = short if sim == "verilator" else dataclasses.replace(short, t_end_s=0.002)
        try:
            c = cocotb_run.run(run_cfg, sim)
        except Exception as e:   # report and go on
            print(f"  cocotb {sim}: failed: {e!r}")
            continue
        _line(f"cocotb {sim}", c)
        n = min(len(c.traj.t), len(ref.traj.t))
        print(f"  {'':<22} telemetry of {n} control samples identical to the native harness: "
              f"{_same_telemetry(c, ref)}")
    return 0 if same else 1


if __name__ == "__main__":
    raise SystemExit(main())
