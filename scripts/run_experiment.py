#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""make run: the paper's experiment and its title question (docs/experiment.md).

    python scripts/run_experiment.py [--quick] [--t-end 40] [--jobs 2] [--out build/report]

1. The characterisation of the experiment arm's plant (the lab's session on
   the simulated bench, pins from the RTL), reused from build/characterize/
   while its inputs are unchanged (make characterize runs the whole study).
2. For P, PD and PID at T = 40 s: the **model arm** (the paper's simulation,
   `paper` plant), the **experiment arm** (the board image and the servo
   firmware in the loop on the `lab` plant, configured from the
   characterisation file as `torqueloop config load` does it) and the **fast
   path** with the same settings (the implementation check).
3. The experiment arm's variants on the fast path: without PW0, at 20 kHz and
   at 50 Hz (carriers the method rejects).
4. The title question: a closed-loop sweep of the PWM carrier (8 carriers,
   50 Hz - 24.4 kHz) x PW0 on/off x the three laws on the fast path.
5. One report in build/report/: report.md, report.json, PNGs.

``--quick`` (make run QUICK=1): T = 2 s, a 3-carrier sweep of P at 1 s, for
a first look in a few minutes.
"""

from __future__ import annotations

import argparse
import json
import math
import multiprocessing as mp
import os
import pickle
import sys
import time
from pathlib import Path

from torqueloop.spec.repo import REPO_ROOT

SWEEP_HZ = (50.0, 120.0, 300.0, 700.0, 1700.0, 4000.0, 10_000.0, 24_400.0)
QUICK_SWEEP_HZ = (50.0, 1700.0, 24_400.0)
VARIANTS = {
    "pw0_off": ("no dead-zone compensation (PW0 = 0)", dict(pw0_off=True)),
    "reject_20khz": ("at 20 kHz, a carrier the method rejects", dict(pwm_hz=(20_000.0, 20_000.0))),
    "reject_50hz": ("at 50 Hz, the lowest of the sweep", dict(pwm_hz=(50.0, 50.0))),
}


def _say(msg: str) -> None:
    print(f"[run] {msg}", flush=True)


def characterization(plant: str, out: Path, quick: bool) -> Path:
    """The experiment arm's characterisation file: reused while its inputs
    are unchanged, else the lab's session is run (pins from the RTL)."""
    from sim_models.variants import parse_plant
    from torqueloop.characterize.cli import main as characterize
    from torqueloop.characterize.simbench import Plant
    from torqueloop.characterize.study import inputs_digest

    name, off = parse_plant(plant)
    source = "model" if quick else "rtl"
    cfg, digest_file = out / "characterization.json", out / "inputs.sha256"
    want = {inputs_digest(Plant(name, off), s) for s in (("model", "rtl") if quick else ("rtl",))}
    if cfg.exists() and digest_file.exists() and digest_file.read_text().strip() in want:
        _say(f"characterisation: {cfg.relative_to(REPO_ROOT)} is current (its inputs are unchanged); reused")
        return cfg
    _say(f"characterisation of the {plant} plant: the lab's session on the simulated bench (pins from {source}) ...")
    rc = characterize(["sim", "--plant", plant, "--source", source, "--seeds", "1", "--no-ablation",
                       "--no-linearity", "--out-dir", str(out)])
    if rc != 0 or not cfg.exists():
        raise SystemExit(f"run_experiment: the characterisation did not write a configuration (exit {rc}); "
                         f"see the log above")
    return cfg


def _job(job: tuple) -> tuple:
    from dataclasses import replace

    from torqueloop.sim import experiment

    kind, key, cfg = job

    t0 = time.monotonic()
    try:
        if kind == "rtl":   # and its implementation check: the fast path with the carriers' phase it met
            rtl = experiment.run_rtl(cfg, log=lambda m, **k: print(f"  {m.strip()}", flush=True))
            run = (rtl, experiment.run_fast(replace(cfg, progress=False), rtl.carrier_start_clk))
        elif kind == "model":
            run = experiment.run_paper_model(cfg)
        else:
            run = experiment.run_fast(cfg)
    except Exception as e:   # noqa: BLE001 - reported by name, the other runs go on
        run = RunFailed(f"{type(e).__name__}: {e}")
    return kind, key, run, time.monotonic() - t0


class RunFailed(str):
    """A run that raised: its one-line reason (the pool goes on with the rest)."""


def main(argv: list[str] | None = None) -> int:
    from dataclasses import replace

    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--quick", action="store_true", help="a short version for a first look (make run QUICK=1)")
    ap.add_argument("--t-end", type=float, default=None, help="T of eq. (26), s [40; quick 2]")
    ap.add_argument("--sweep-t-end", type=float, default=None, help="T of each sweep run, s [10; quick 1]")
    ap.add_argument("--laws", nargs="+", default=["P", "PD", "PID"], choices=["P", "PD", "PID"])
    ap.add_argument("--model-plant", default="paper", help="the model arm's plant variant [paper]")
    ap.add_argument("--experiment-plant", default="lab", help="the experiment arm's plant variant [lab]")
    ap.add_argument("--char-dir", type=Path, default=REPO_ROOT / "build" / "characterize")
    ap.add_argument("--jobs", type=int, default=os.cpu_count() or 2, help="runs in parallel [cores]")
    ap.add_argument("--out", type=Path, default=REPO_ROOT / "build" / "report")
    a = ap.parse_args(argv)
    from sim_models.params import PlantParamError
    from sim_models.variants import parse_plant
    from torqueloop.sim import experiment, native, report

    for p in (a.model_plant, a.experiment_plant):
        try:
            parse_plant(p)
        except PlantParamError as e:
            print(f"run_experiment: {e}", file=sys.stderr)
            return 2
    t_end = a.t_end if a.t_end is not None else (2.0 if a.quick else 40.0)
    t_sweep = a.sweep_t_end if a.sweep_t_end is not None else (1.0 if a.quick else 10.0)
    if t_end <= 0 or t_sweep <= 0:
        print("run_experiment: --t-end and --sweep-t-end must be positive", file=sys.stderr)
        return 2
    t0 = time.monotonic()
    char = characterization(a.experiment_plant, a.char_dir, a.quick)
    _say("building the board harness and the firmware ...")
    native.build()
    experiment.firmware_image()

    base = experiment.ExperimentConfig(t_end_s=t_end, progress=True)
    exp = replace(base, plant=a.experiment_plant, char_config=str(char))
    jobs: list[tuple] = []
    for law in a.laws:            # the long ones first
        jobs.append(("rtl", (law,), replace(exp, law=law)))
    for law in a.laws:
        jobs.append(("model", (law,), replace(base, law=law, plant=a.model_plant)))
        for name, (_, kw) in VARIANTS.items():
            jobs.append(("fast", ("variant", name, law), replace(exp, law=law, progress=False, **kw)))
    sweep_laws = ["P"] if a.quick else a.laws
    for f in (QUICK_SWEEP_HZ if a.quick else SWEEP_HZ):
        for law in sweep_laws:
            for pw0 in (True, False):
                jobs.append(("fast", ("sweep", f, pw0, law),
                             replace(exp, law=law, t_end_s=t_sweep, pwm_hz=(f, f), pw0_off=not pw0, progress=False)))
    _say(f"{len(jobs)} runs on {a.jobs} processes: {len(a.laws)} x experiment arm (RTL, T = {t_end:g} s, "
         f"then its implementation check), model arm and {len(VARIANTS)} variants per law, "
         f"{sum(j[1][0] == 'sweep' for j in jobs if j[0] == 'fast')} sweep runs (T = {t_sweep:g} s)")
    st = report.Study(t_end_s=t_end, target_rad=base.target_counts * 2 * math.pi / experiment.COUNTS_PER_REV,
                      laws=list(a.laws), sweep_t_end_s=t_sweep,
                      variant_labels={k: v[0] for k, v in VARIANTS.items()})
    done, failed = 0, []
    ctx = mp.get_context("fork")
    with ctx.Pool(max(1, a.jobs)) as pool:
        for kind, key, run, dt in pool.imap_unordered(_job, jobs, chunksize=1):
            done += 1
            what = f"{kind} {' '.join(map(str, key))}"
            if isinstance(run, RunFailed):
                failed.append(f"{what}: {run}")
                _say(f"{done}/{len(jobs)} {what} FAILED after {dt:.0f} s: {run}")
                continue
            _say(f"{done}/{len(jobs)} {what} ({dt:.0f} s; {time.monotonic() - t0:.0f} s so far)")
            if kind == "rtl":
                st.experiment_arm[key[0]], st.fast_check[key[0]] = run
            elif kind == "model":
                st.model_arm[key[0]] = run
            elif key[0] == "variant":
                st.variants.setdefault(key[1], {})[key[2]] = run
            else:
                st.sweep.append((key[1], key[2], key[3], run))
    if failed:
        for f in failed:
            print(f"run_experiment: {f}", file=sys.stderr)
        print(f"run_experiment: {len(failed)} of {len(jobs)} runs failed; no report written", file=sys.stderr)
        return 1
    st.sweep.sort(key=lambda r: (r[0], not r[1], r[2]))
    cfgdoc = json.loads(char.read_text())
    st.characterization = {
        "config": str(char.relative_to(REPO_ROOT) if char.is_relative_to(REPO_ROOT) else char),
        "source": f"plant {a.experiment_plant}, simulated bench",
        "axes": {k: {f: v[f] for f in ("pwm_freq_hz", "achieved_hz", "pw0_counts", "tau_max_nm", "count_max")}
                 for k, v in cfgdoc["axes"].items()},
        "plots": [str(p) for p in sorted((a.char_dir / "plots").glob("*.png"))],
    }
    st.meta = {"model_plant": a.model_plant, "experiment_plant": a.experiment_plant, "quick": a.quick,
               "jobs": a.jobs, "wall_s_total": round(time.monotonic() - t0, 1)}
    a.out.mkdir(parents=True, exist_ok=True)
    (a.out / "data").mkdir(exist_ok=True)
    with open(a.out / "data" / "runs.pkl", "wb") as fh:      # for re-scoring without re-simulating
        pickle.dump(st, fh)
    report.write(st, a.out)
    print((a.out / "report.md").read_text())
    _say(f"report: {a.out}/report.md, report.json, PNGs ({time.monotonic() - t0:.0f} s)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
