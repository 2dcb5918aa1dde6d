# SPDX-License-Identifier: MIT
"""Steps 2-7's verdict per axis and step 8: what ``characterize run`` and the
characterisation study both do with a session's results (print each axis's
report and plots, then write the configuration file only if every axis
passed; the exit status says why not)."""

from __future__ import annotations

import sys
from pathlib import Path

from torqueloop.spec.charconfig import load_config, write_config

from .config import CLK_HZ, PWM_BITS, axis_config, build_config
from .method import MotorResult, Thresholds

#: exit statuses: every axis passed and the file was written; bad data or the
#: method cannot proceed; a duty sweep must be recorded; step 7 failed at every candidate
EXIT_OK, EXIT_ERROR, EXIT_NEED_SWEEP, EXIT_FAIL = 0, 1, 2, 3


def report(name: str, r: MotorResult) -> str:
    lines = [f"[{name}] motor {r.freq_sweep.motor!r}: tau_max = {r.step5.tau_max_nm:.4g} N m (step 2)",
             f"[{name}] step 5: {r.step5.message}"]
    for c in r.step5.candidates[:5]:
        lines.append(f"[{name}]   candidate {c.freq_hz:9.4f} Hz  ({c.kind}, slope {c.slope_nm_per_hz:+.3g} N m/Hz)")
    if len(r.step5.candidates) > 5:
        lines.append(f"[{name}]   ... and {len(r.step5.candidates) - 5} more")
    for a in r.attempts:
        if a.linearity is None:
            continue
        lin = a.linearity
        lines.append(f"[{name}] steps 6-7 at {lin.freq_hz:.4g} Hz ({a.duty_sweep.source if a.duty_sweep else ''}): "
                     f"{'PASS' if lin.ok else 'FAIL'}")
        for ch in lin.checks:
            lines.append(f"[{name}]     {'ok  ' if ch.ok else 'FAIL'} {ch.text}")
        if lin.pw0_pct == lin.pw0_pct:  # not NaN: a line was fitted
            lines.append(f"[{name}]     dead zone PW0 = {lin.pw0_pct:.2f} %, PW_F = {lin.pwf_pct:.2f} %")
    for u in r.unused_duty_sweeps:
        lines.append(f"[{name}] note: {u} matched no candidate it was needed for")
    lines.append(f"[{name}] {r.status}: {r.message}")
    return "\n".join(lines)


def conclude(results: dict[str, MotorResult], data_dir: Path, out: Path, plots: str | Path | None,
             th: Thresholds, clk_hz: int = CLK_HZ, pwm_bits: int = PWM_BITS) -> int:
    """Steps 2-7's report per axis, the plots, and step 8: the configuration
    file, written only if every axis passed (the exit status says why not)."""
    worst = EXIT_OK
    for name, r in results.items():
        print(report(name, r), flush=True)
        if plots:
            from .plots import plot_result

            for p in plot_result(r, plots, name):
                print(f"[{name}] plot {p}")
        if r.status == "need_duty_sweep":
            worst = max(worst, EXIT_NEED_SWEEP)
        elif r.status == "fail":
            worst = max(worst, EXIT_FAIL)
    if worst != EXIT_OK:
        print("no configuration written: not every axis passed", file=sys.stderr)
        return worst
    axes = {n: axis_config(r, clk_hz=clk_hz, pwm_bits=pwm_bits, base_dir=data_dir) for n, r in results.items()}
    cfg = build_config(axes, th, clk_hz=clk_hz, pwm_bits=pwm_bits)
    write_config(out, cfg)
    load_config(out)  # what we write must be what the readers accept
    for n, a in cfg.axes.items():
        print(f"[{n}] step 8: {a.pwm_freq_hz:.6g} Hz -> count_max {a.count_max} -> {a.achieved_hz:.6g} Hz "
              f"({a.freq_error_pct:+.3f} %), PW0 {a.pw0_counts} / PW_F {a.pw_max_counts} counts of {(1 << pwm_bits) - 1}")
    print(f"wrote {out}")
    return EXIT_OK
