# SPDX-License-Identifier: MIT
"""The carrier sweep's dead zones: the paper's dead zone (raise the pulse
until the stage moves, lower it until it stops:
:func:`torqueloop.characterize.simbench.motion_dead_zones`) per axis and
carrier, as PW0 counts.  One PW0 per axis drives both directions; it is the
lower of the two directions' stop duties (a PW0 above either would push that
direction past its dead zone), rounded up to whole counts as step 8 rounds
the intercept.  Cached in build/characterize/dead_zones.json while the
inputs' digest, this module and the carriers are unchanged."""

from __future__ import annotations

import math
import time
from pathlib import Path
from typing import Any, Sequence

from sim_models.variants import PlantSpec
from torqueloop.characterize.config import CLK_HZ, PWM_BITS
from torqueloop.characterize.simbench import motion_dead_zones
from torqueloop.spec.pwm import carrier_hz, divider_for, full_scale
from torqueloop.study.cache import cached
from torqueloop.study.engine import Engine, Progress

AXES = ("x", "z")


def pw0_counts(stop_pcts: Sequence[float]) -> int:
    """One PW0 for both directions: the lower stop duty, rounded up to counts."""
    return int(math.ceil(min(stop_pcts) / 100.0 * full_scale(PWM_BITS) - 1e-9))


def _dz_job(job: tuple[PlantSpec, str, float]) -> dict[str, Any]:
    plant, axis, f = job
    t0 = time.process_time()
    dz = motion_dead_zones(plant, [f], axes=(axis,))
    return {"axis": axis, "freq_hz": f, "board_hz": carrier_hz(divider_for(f, CLK_HZ, PWM_BITS), CLK_HZ, PWM_BITS),
            "stop_pct": {("forward" if d.direction > 0 else "reverse"): d.stop_pct for d in dz},
            "start_pct": {("forward" if d.direction > 0 else "reverse"): d.start_pct for d in dz},
            "pw0_counts": pw0_counts([d.stop_pct for d in dz]), "cpu_s": time.process_time() - t0}


def dead_zones(plant: PlantSpec, freqs_hz: Sequence[float], cache: Path, digest: str, engine: Engine = Engine(),
               say=print) -> dict[str, Any]:
    """``{"rows": [...], "pw0": {freq: (x counts, z counts)}}``, reused from
    ``cache`` while the inputs' digest and the carriers are unchanged."""
    jobs = [(plant, a, float(f)) for f in freqs_hz for a in AXES]

    def compute() -> dict[str, Any]:
        say(f"dead zones per carrier: {len(jobs)} motion ramps (raise until the stage moves, lower until it stops) "
            f"on the {engine.name}")
        rows, progress = [], Progress([1.0] * len(jobs), engine.workers)
        for k, (_, r) in enumerate(engine.map_unordered(_dz_job, jobs), 1):
            rows.append(r)
            say(f"dead zone {k}/{len(jobs)}: axis {r['axis']} at {r['board_hz']:.4g} Hz: PW0 {r['pw0_counts']} "
                f"counts ({progress.line(1.0, r['cpu_s'])})")
        rows.sort(key=lambda r: (r["freq_hz"], r["axis"]))
        pw0 = {str(float(f)): [next(r["pw0_counts"] for r in rows if r["freq_hz"] == f and r["axis"] == a)
                               for a in AXES] for f in freqs_hz}
        return {"rows": rows, "pw0": pw0, "cpu_s": sum(r["cpu_s"] for r in rows)}

    doc = cached(cache, digest, __file__, repr((plant.label, tuple(freqs_hz))), compute,
                 say=lambda m: say(f"dead zones per carrier: {m}"))
    return doc | {"pw0": {float(k): tuple(v) for k, v in doc["pw0"].items()}}
