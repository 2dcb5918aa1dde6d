# SPDX-License-Identifier: MIT
"""The ``torqueloop-study`` command: the studies behind ``make run`` and
``make characterize``.

    torqueloop-study experiment [--quick] [--t-end 40] [--sweep-t-end 10] [--laws P PD PID]
                                [--model-plant paper] [--experiment-plant lab] [--jobs N] [--cluster ADDR]
                                [--out build/report]
    torqueloop-study characterize run|sim|step5|check|show|export ...   (characterize --help)

This module only parses: a plant name becomes a
:class:`~sim_models.variants.PlantSpec` here, the options an
:class:`~torqueloop.study.experiment.ExperimentPlan`; a bad option is one
line and exit status 2.
"""

from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path
from typing import Sequence

from sim_models.params import PlantParamError
from sim_models.variants import plant_choice, plant_of
from torqueloop.spec.repo import REPO_ROOT
from torqueloop.study import characterize_cli
from torqueloop.study import experiment as experiment_study
from torqueloop.study.engine import EngineError
from torqueloop.study.experiment import LAWS, ExperimentPlan, run_experiment


def experiment(argv: Sequence[str]) -> int:
    ap = argparse.ArgumentParser(prog="torqueloop-study experiment", description=experiment_study.__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--quick", action="store_true", help="a short version for a first look (make run QUICK=1)")
    ap.add_argument("--thorough", action="store_true",
                    help="the carrier sweep as the question needs it: PD and PID at T = 40 s, two step sizes, "
                         "three start positions (hours on 2 cores)")
    ap.add_argument("--t-end", type=float, default=None, help="T of eq. (26), s [40; quick 2]")
    ap.add_argument("--sweep-t-end", type=float, default=None, help="T of each sweep run, s [10; quick 1]")
    ap.add_argument("--laws", nargs="+", default=list(LAWS), choices=LAWS)
    ap.add_argument("--model-plant", default="paper", help="the model arm's plant variant [paper]")
    ap.add_argument("--experiment-plant", default=None, help="the experiment arm's plant variant [lab]")
    ap.add_argument("--experiment-plant-file", default=os.environ.get("TORQUELOOP_PLANT_FILE") or None,
                    metavar="FILE", help="the experiment arm's plant from a plant file (make run PLANT_FILE=...)")
    ap.add_argument("--char-dir", type=Path, default=REPO_ROOT / "build" / "characterize")
    ap.add_argument("--jobs", type=int, default=os.cpu_count() or 2, help="runs in parallel [cores]")
    ap.add_argument("--cluster", default=os.environ.get("TORQUELOOP_CLUSTER") or None, metavar="tcp://HOST:8786",
                    help="run on a Dask scheduler's workers instead of the local pool (docs/experiment.md, "
                         "'On a cluster')")
    ap.add_argument("--out", type=Path, default=REPO_ROOT / "build" / "report")
    a = ap.parse_args(argv)
    try:
        kw = dict(laws=tuple(a.laws), model_plant=plant_of(a.model_plant),
                  experiment_plant=plant_choice(a.experiment_plant, a.experiment_plant_file, default="lab"), char_dir=a.char_dir, jobs=max(1, a.jobs),
                  out=a.out, cluster=a.cluster)
    except PlantParamError as e:
        return _refuse(f"experiment: {e}")
    if a.t_end is not None:
        kw["t_end_s"] = a.t_end
    if a.sweep_t_end is not None:
        kw["sweep_t_end_s"] = a.sweep_t_end
    if a.quick and a.thorough:
        return _refuse("experiment: --quick and --thorough exclude each other")
    plan = ExperimentPlan.short(**kw) if a.quick else ExperimentPlan.thorough(**kw) if a.thorough else ExperimentPlan(**kw)
    try:
        plan.check()
    except ValueError as e:
        return _refuse(f"experiment: {e}")
    try:
        return run_experiment(plan)
    except EngineError as e:
        return _refuse(f"experiment: {e}")
    except RuntimeError as e:
        print(f"torqueloop-study: experiment: {e}", file=sys.stderr)
        return 1


def _refuse(msg: str) -> int:
    print(f"torqueloop-study: {msg}", file=sys.stderr)
    return 2


STUDIES = {"experiment": experiment, "characterize": characterize_cli.main}


def main(argv: Sequence[str] | None = None) -> int:
    argv = list(sys.argv[1:] if argv is None else argv)
    if argv[:1] in (["-h"], ["--help"]):
        print(__doc__)
        return 0
    if not argv:
        return _refuse(f"name a study ({', '.join(STUDIES)}); --help for the options")
    study = STUDIES.get(argv[0])
    if study is None:
        return _refuse(f"unknown study {argv[0]!r} (known: {', '.join(STUDIES)})")
    return int(study(argv[1:]))


if __name__ == "__main__":
    sys.exit(main())
