# SPDX-License-Identifier: MIT
"""``torqueloop-study characterize``: the characterisation command
(torqueloop/characterize/command.py) with the study's ``sim``: the method on
the simulated bench, then the study around it (instrument seeds, linearity
at other carriers, each plant effect off; torqueloop/study/characterization.py)."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Sequence

from torqueloop.characterize import command
from torqueloop.characterize.command import EXIT_ERROR, EXIT_FAIL, EXIT_NEED_SWEEP, EXIT_OK  # noqa: F401
from torqueloop.study import stability, uncertainty
from torqueloop.study.characterization import LINEARITY_FREQS_HZ, run_study
from torqueloop.study.engine import Engine


def run_sim(args: argparse.Namespace) -> int:
    """``characterize sim`` (arguments checked by the command)."""
    return run_study(Path(args.out_dir), args.plant, seeds=args.seeds, axes=args.axes,
                     source=args.source, sim=args.simulator, th=args.thresholds, ablation=args.ablation,
                     linearity_freqs=LINEARITY_FREQS_HZ if args.linearity else (),
                     stability_plan={"full": stability.FULL, "quick": stability.QUICK, "off": None}[args.stability],
                     uncertainty_plan={"full": uncertainty.FULL, "quick": uncertainty.QUICK,
                                       "off": None}[args.uncertainty],
                     engine=Engine(max(1, args.jobs)))


def main(argv: Sequence[str] | None = None) -> int:
    return command.main(argv, sim=run_sim, prog="torqueloop-study characterize")


if __name__ == "__main__":
    sys.exit(main())
