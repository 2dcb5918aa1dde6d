# SPDX-License-Identifier: MIT
"""The characterisation command: ``torqueloop characterize`` (the lab tool, a host
install: lab CSVs in, the configuration out) and ``torqueloop-study characterize``
(the same, and ``sim``: the method on the simulated bench with the study around it).

    characterize run DATA_DIR [--out CONFIG] [--plots DIR] [--set NAME=VALUE ...]
    characterize sim [--plant lab] [--seeds 10] [--out-dir DIR] [--source rtl|model] [--axes x z]
                     [--no-ablation] [--no-linearity]
    characterize step5 FREQ_SWEEP.csv
    characterize check FILE.csv ...
    characterize show CONFIG.json [--registers]
    characterize export CONFIG.json --format c|verilog --out FILE

``sim`` records the sweeps on the simulated bench (the plant variant's
motor on the rope dynamometer, driven by the RTL's pins or their documented
waveform, read through seeded instruments) into ``DIR/data/<axis>/`` and
then does exactly what ``run`` does with them, writing
``DIR/characterization.json`` and the plots in ``DIR/plots``; then the
study: the session with other instrument seeds, linearity at other
frequencies and each plant effect off (``DIR/results.{json,md}``,
torqueloop/study/characterization.py).  The study passes its ``sim`` to
:func:`main` (the characterisation layer does not reach up into the study);
without it ``sim`` says where it lives.

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
from typing import Callable, Sequence

from sim_models.params import PlantParamError
from sim_models.variants import plant_choice
from torqueloop.characterize.conclude import EXIT_ERROR, EXIT_FAIL, EXIT_NEED_SWEEP, EXIT_OK, conclude
from torqueloop.characterize.config import CLK_HZ, PWM_BITS
from torqueloop.characterize.data import DataError, Sweep, read_sweep
from torqueloop.flow.gen_charconfig import c_header, verilog_header
from torqueloop.characterize.method import MethodError, MotorResult, Thresholds, characterize_motor, step5_candidates
from torqueloop.spec.charconfig import ConfigError, load_config, register_writes
from torqueloop.spec.pwm import carrier_hz, divider_for

__all__ = ["EXIT_OK", "EXIT_ERROR", "EXIT_NEED_SWEEP", "EXIT_FAIL", "main"]


def _error(message: object) -> int:
    """One line on stderr; the exit status of bad input."""
    print(message, file=sys.stderr)
    return EXIT_ERROR


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


def cmd_run(args: argparse.Namespace) -> int:
    th = _thresholds(args.set)
    data_dir = Path(args.data_dir)
    results: dict[str, MotorResult] = {}
    for name, files in _axes(data_dir, args.axis).items():
        try:
            fs, ds = _split(files)
            results[name] = characterize_motor(fs, ds, th)
        except (DataError, MethodError) as e:
            return _error(f"[{name}] error: {e}")
    return conclude(results, data_dir, Path(args.out), args.plots, th, args.clk_hz, args.pwm_bits)


#: ``sim``'s runner: (args) -> exit status; the study's, when it calls :func:`main`
SimRunner = Callable[[argparse.Namespace], int]


def _no_sim(args: argparse.Namespace) -> int:
    print("error: `characterize sim` is the study's: torqueloop-study characterize sim "
          "(needs the simulation stack: pip install 'torqueloop[sim]')", file=sys.stderr)
    return EXIT_ERROR


def check_sim_args(args: argparse.Namespace) -> int | None:
    """The ``sim`` arguments checked (an exit status if bad, else None)."""
    try:
        plant = plant_choice(args.plant, args.plant_file, default="lab")
    except PlantParamError as e:
        return _error(f"error: --plant: {e}")
    if args.seeds < 1:
        return _error("error: --seeds must be at least 1")
    args.plant = plant
    args.thresholds = _thresholds(args.set)
    return None


def cmd_step5(args: argparse.Namespace) -> int:
    th = _thresholds(args.set)
    try:
        fs = read_sweep(args.freq_sweep)
        s5 = step5_candidates(fs, th)
    except (DataError, MethodError) as e:
        return _error(f"error: {e}")
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
            rc = _error(f"error: {e}")
    return rc


def cmd_show(args: argparse.Namespace) -> int:
    try:
        cfg = load_config(args.config)
    except ConfigError as e:
        return _error(f"error: {e}")
    print(f"{args.config}: schema v{cfg.schema_version}, clk {cfg.clk_hz} Hz, {cfg.pwm_bits}-bit PWM")
    for n, a in cfg.axes.items():
        print(f"  {n}: {a.pwm_freq_hz:g} Hz, count_max {a.count_max} ({a.achieved_hz:.6g} Hz, {a.freq_error_pct:+.3f} %), "
              f"PW0 {a.pw0_counts}, PW_F {a.pw_max_counts}, tau_max {a.tau_max_nm:g} N m")
    if args.registers:
        try:
            for reg, addr, val in register_writes(cfg):
                print(f"  write {reg:<16} 0x{addr:08X} = {val}")
        except ConfigError as e:
            return _error(f"error: {e}")
    return EXIT_OK


def cmd_export(args: argparse.Namespace) -> int:
    try:
        cfg = load_config(args.config)
        text = (c_header if args.format == "c" else verilog_header)(cfg, Path(args.config).name)
    except ConfigError as e:
        return _error(f"error: {e}")
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(text)
    print(f"wrote {out}")
    return EXIT_OK


def main(argv: Sequence[str] | None = None, sim: SimRunner | None = None,
         prog: str = "torqueloop characterize") -> int:
    ap = argparse.ArgumentParser(prog=prog, description=__doc__,
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
    p.add_argument("--plant", default=None,
                   help="plant variant: paper-printed, paper or lab; lab-no-EFFECT[-no-EFFECT] switches "
                        "lab effects off (sim_models/params/variants.toml) [lab]")
    p.add_argument("--plant-file", default=None, metavar="FILE", help="a plant file instead of a variant")
    p.add_argument("--seeds", type=int, default=10, help="sessions with different instrument noise [10]")
    p.add_argument("--no-ablation", dest="ablation", action="store_false",
                   help="skip the runs with each plant effect off")
    p.add_argument("--no-linearity", dest="linearity", action="store_false",
                   help="skip the duty sweeps at other frequencies than the chosen one")
    p.add_argument("--source", choices=("rtl", "model"), default="rtl",
                   help="pins from the RTL in simulation (default) or from the cores' documented waveform")
    p.add_argument("--simulator", default="verilator", choices=("verilator", "icarus"))
    p.add_argument("--axes", nargs="+", default=["x", "z"])
    p.add_argument("--stability", choices=("full", "quick", "off"), default="off",
                   help="the chosen carrier under each bench protocol (settle, sweep order); make characterize: full [off]")
    p.add_argument("--uncertainty", choices=("full", "quick", "off"), default="off",
                   help="the chosen carrier under the plant's parameter uncertainty (Monte Carlo); "
                        "make characterize: full [off]")
    p.add_argument("--jobs", type=int, default=2, help="sweeps of the stability and uncertainty tables run in "
                                                       "parallel [2]")
    p.add_argument("--set", action="append", default=[], metavar="NAME=VALUE")
    p.set_defaults(fn=lambda args: check_sim_args(args) or (sim or _no_sim)(args))
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
