# SPDX-License-Identifier: MIT
"""The characterisation command (scripts/characterize.py).

    characterize.py run DATA_DIR [--out CONFIG] [--plots DIR] [--set NAME=VALUE ...]
    characterize.py sim [--plant lab] [--seeds 10] [--out-dir DIR] [--source rtl|model] [--axes x z]
                        [--no-ablation] [--no-linearity]
    characterize.py step5 FREQ_SWEEP.csv
    characterize.py check FILE.csv ...
    characterize.py show CONFIG.json [--registers]
    characterize.py export CONFIG.json --format c|verilog --out FILE

``sim`` records the sweeps on the simulated bench (the plant variant's
motor on the rope dynamometer, driven by the RTL's pins or their documented
waveform, read through seeded instruments) into ``DIR/data/<axis>/`` and
then does exactly what ``run`` does with them, writing
``DIR/characterization.json`` and the plots in ``DIR/plots``; then the
study: the session with other instrument seeds, linearity at other
frequencies and each plant effect off (``DIR/results.{json,md}``,
torqueloop/characterize/study.py).

``run`` takes one folder per axis (``DATA_DIR/<axis>/*.csv``: one frequency
sweep and any number of duty sweeps, recognised by their ``# sweep =``
line), or a folder of CSVs for a single axis (named by ``--axis``).

Exit status: 0 every axis passed and the configuration was written;
1 bad data or the method cannot proceed; 2 a duty sweep must be recorded
(the message says at which frequency); 3 step 7 failed at every candidate.
"""

from __future__ import annotations

import argparse
import dataclasses
import sys
from pathlib import Path
from typing import Sequence

from torqueloop.spec.charconfig import ConfigError, load_config, register_writes, write_config
from torqueloop.spec.pwm import carrier_hz, divider_for

from .config import CLK_HZ, PWM_BITS, axis_config, build_config, c_header, verilog_header
from .data import DataError, Sweep, read_sweep
from .method import MethodError, MotorResult, Thresholds, characterize_motor, step5_candidates

EXIT_OK, EXIT_ERROR, EXIT_NEED_SWEEP, EXIT_FAIL = 0, 1, 2, 3


def _thresholds(sets: Sequence[str]) -> Thresholds:
    th = Thresholds()
    names = {f.name: f.type for f in dataclasses.fields(Thresholds)}
    for s in sets:
        if "=" not in s:
            raise SystemExit(f"--set {s!r}: use NAME=VALUE")
        k, v = (x.strip() for x in s.split("=", 1))
        if k not in names:
            raise SystemExit(f"--set {k}: unknown threshold (known: {', '.join(names)})")
        cast = int if k == "min_moving_points" else float
        th = dataclasses.replace(th, **{k: cast(v)})
    return th


def _axes(data_dir: Path, axis: str | None) -> dict[str, list[Path]]:
    if not data_dir.is_dir():
        raise SystemExit(f"{data_dir}: not a folder")
    direct = sorted(data_dir.glob("*.csv"))
    if direct:
        return {axis or data_dir.name.lower(): direct}
    found = {d.name.lower(): sorted(d.glob("*.csv")) for d in sorted(data_dir.iterdir()) if d.is_dir()}
    found = {k: v for k, v in found.items() if v}
    if not found:
        raise SystemExit(f"{data_dir}: no CSV files (expected <axis>/*.csv or *.csv)")
    return found


def _split(files: Sequence[Path]) -> tuple[Sweep, list[Sweep]]:
    sweeps = [read_sweep(f) for f in files]
    freq = [s for s in sweeps if s.kind == "frequency"]
    if len(freq) != 1:
        where = ", ".join(s.source for s in freq) or "none"
        raise MethodError(f"need exactly one frequency sweep per axis, found {len(freq)} ({where})")
    return freq[0], [s for s in sweeps if s.kind == "duty"]


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


def cmd_run(args: argparse.Namespace) -> int:
    th = _thresholds(args.set)
    data_dir = Path(args.data_dir)
    results: dict[str, MotorResult] = {}
    for name, files in _axes(data_dir, args.axis).items():
        try:
            fs, ds = _split(files)
            results[name] = characterize_motor(fs, ds, th)
        except (DataError, MethodError) as e:
            print(f"[{name}] error: {e}", file=sys.stderr)
            return EXIT_ERROR
    return conclude(results, data_dir, Path(args.out), args.plots, th, args.clk_hz, args.pwm_bits)


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


def cmd_sim(args: argparse.Namespace) -> int:
    from sim_models.params import PlantParamError
    from sim_models.variants import parse_plant

    from .simbench import Plant
    from .study import run_study

    try:
        name, off = parse_plant(args.plant)
    except PlantParamError as e:
        print(f"error: --plant: {e}", file=sys.stderr)
        return EXIT_ERROR
    if args.seeds < 1:
        print("error: --seeds must be at least 1", file=sys.stderr)
        return EXIT_ERROR
    from .study import LINEARITY_FREQS_HZ

    return run_study(Path(args.out_dir), Plant(name, off), seeds=args.seeds, axes=args.axes,
                     source=args.source, sim=args.simulator, th=_thresholds(args.set), ablation=args.ablation,
                     linearity_freqs=LINEARITY_FREQS_HZ if args.linearity else ())


def cmd_step5(args: argparse.Namespace) -> int:
    th = _thresholds(args.set)
    try:
        fs = read_sweep(args.freq_sweep)
        s5 = step5_candidates(fs, th)
    except (DataError, MethodError) as e:
        print(f"error: {e}", file=sys.stderr)
        return EXIT_ERROR
    print(f"tau_max = {s5.tau_max_nm:.4g} N m, target {s5.target_nm:.4g} N m: {s5.message}")
    for i, c in enumerate(s5.candidates, 1):
        cm = divider_for(c.freq_hz, args.clk_hz, args.pwm_bits)
        ach = carrier_hz(cm, args.clk_hz, args.pwm_bits)
        print(f"{i}. {c.freq_hz:.4f} Hz ({c.kind}); on the board: count_max {cm} gives {ach:.4f} Hz "
              f"- record the duty sweep there")
    return EXIT_OK


def cmd_check(args: argparse.Namespace) -> int:
    rc = EXIT_OK
    for f in args.files:
        try:
            s = read_sweep(f)
            extra = f"at {s.freq_hz:g} Hz" if s.kind == "duty" else f"tau_max {s.stall_torque_nm:.4g} N m"
            print(f"{f}: ok, {s.kind} sweep, {len(s.x)} points, {extra}")
        except DataError as e:
            print(f"error: {e}", file=sys.stderr)
            rc = EXIT_ERROR
    return rc


def cmd_show(args: argparse.Namespace) -> int:
    try:
        cfg = load_config(args.config)
    except ConfigError as e:
        print(f"error: {e}", file=sys.stderr)
        return EXIT_ERROR
    print(f"{args.config}: schema v{cfg.schema_version}, clk {cfg.clk_hz} Hz, {cfg.pwm_bits}-bit PWM")
    for n, a in cfg.axes.items():
        print(f"  {n}: {a.pwm_freq_hz:g} Hz, count_max {a.count_max} ({a.achieved_hz:.6g} Hz, {a.freq_error_pct:+.3f} %), "
              f"PW0 {a.pw0_counts}, PW_F {a.pw_max_counts}, tau_max {a.tau_max_nm:g} N m")
    if args.registers:
        try:
            for reg, addr, val in register_writes(cfg):
                print(f"  write {reg:<16} 0x{addr:08X} = {val}")
        except ConfigError as e:
            print(f"error: {e}", file=sys.stderr)
            return EXIT_ERROR
    return EXIT_OK


def cmd_export(args: argparse.Namespace) -> int:
    try:
        cfg = load_config(args.config)
        text = (c_header if args.format == "c" else verilog_header)(cfg, Path(args.config).name)
    except ConfigError as e:
        print(f"error: {e}", file=sys.stderr)
        return EXIT_ERROR
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(text)
    print(f"wrote {out}")
    return EXIT_OK


def main(argv: Sequence[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="characterize", description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = ap.add_subparsers(dest="cmd", required=True)

    def common(p: argparse.ArgumentParser) -> None:
        p.add_argument("--set", action="append", default=[], metavar="NAME=VALUE",
                       help="override a threshold (see docs/characterization.md)")
        p.add_argument("--clk-hz", type=int, default=CLK_HZ)
        p.add_argument("--pwm-bits", type=int, default=PWM_BITS)

    p = sub.add_parser("run", help="steps 2-8 on a data folder; writes the configuration")
    p.add_argument("data_dir")
    p.add_argument("--out", default="characterization.json")
    p.add_argument("--plots", default=None, help="folder for Fig. 10/11 style PNGs")
    p.add_argument("--axis", default=None, help="axis name when DATA_DIR holds one axis's CSVs")
    common(p)
    p.set_defaults(fn=cmd_run)
    p = sub.add_parser("sim", help="the whole method on the simulated bench (no hardware), and the study around it")
    p.add_argument("--out-dir", default="build/characterize")
    p.add_argument("--plant", default="lab",
                   help="plant variant: paper-printed, paper or lab; lab-no-EFFECT[-no-EFFECT] switches "
                        "lab effects off (sim_models/params/variants.toml) [lab]")
    p.add_argument("--seeds", type=int, default=10, help="sessions with different instrument noise [10]")
    p.add_argument("--no-ablation", dest="ablation", action="store_false",
                   help="skip the runs with each plant effect off")
    p.add_argument("--no-linearity", dest="linearity", action="store_false",
                   help="skip the duty sweeps at other frequencies than the chosen one")
    p.add_argument("--source", choices=("rtl", "model"), default="rtl",
                   help="pins from the RTL in simulation (default) or from the cores' documented waveform")
    p.add_argument("--simulator", default="verilator", choices=("verilator", "icarus"))
    p.add_argument("--axes", nargs="+", default=["x", "z"])
    p.add_argument("--set", action="append", default=[], metavar="NAME=VALUE")
    p.set_defaults(fn=cmd_sim)
    p = sub.add_parser("step5", help="candidate frequencies from a frequency sweep")
    p.add_argument("freq_sweep")
    common(p)
    p.set_defaults(fn=cmd_step5)
    p = sub.add_parser("check", help="validate sweep files")
    p.add_argument("files", nargs="+")
    p.set_defaults(fn=cmd_check)
    p = sub.add_parser("show", help="validate and summarise a configuration file")
    p.add_argument("config")
    p.add_argument("--registers", action="store_true", help="list the SoC register writes that apply it")
    p.set_defaults(fn=cmd_show)
    p = sub.add_parser("export", help="C header (firmware) or Verilog `defines (RTL) from a configuration")
    p.add_argument("config")
    p.add_argument("--format", choices=("c", "verilog"), default="c")
    p.add_argument("--out", required=True)
    p.set_defaults(fn=cmd_export)
    args = ap.parse_args(argv)
    return int(args.fn(args))


if __name__ == "__main__":
    sys.exit(main())
