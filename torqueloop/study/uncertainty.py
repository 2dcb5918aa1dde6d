# SPDX-License-Identifier: MIT
"""The characterisation's answer under the plant's parameter uncertainty: a
Monte Carlo over stated ranges of the values no datasheet gives for this
motor (:data:`RANGES`), each draw's `lab` plant through the same step 5
(:func:`torqueloop.study.stability.step5_on`, one bench protocol) and the
paper's dead zone at the carrier it chose.

The interval reported is the range (and the 10-90 % percentiles, when
there are at least 10 draws) of the chosen carrier over the draws: the
spread that the stated parameter ranges give, with every value in its range
equally likely (log-uniform for factors). It is named for what it is - a
parameter-uncertainty interval over assumed ranges - beside the
instrument-noise interval of the repeatability seeds, which varies only the
gauge's and ammeter's noise.  The seed is printed and recorded.
"""

from __future__ import annotations

import math
import random
import time
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any, Sequence

import numpy as np

from sim_models.variants import PlantSpec
from torqueloop.characterize.method import motion_dead_zone
from torqueloop.characterize.simbench import MotionRamp, model_waveform, record_motion_ramp
from torqueloop.characterize.config import CLK_HZ, PWM_BITS
from torqueloop.spec.pwm import divider_for
from torqueloop.study.engine import Engine, Progress
from torqueloop.study.stability import CarriedBench, Protocol, step5_on

#: name -> (low, high, how it is applied, why this range)
RANGES: dict[str, tuple[float, float, str, str]] = {
    "coulomb_frac": (0.02, 0.045, "motor_friction.coulomb_frac (breakaway 1.4 x)",
                     "the no-load current 0.15-0.2 A of 5.5 A stall, all or half of it friction"),
    "brush_volts": (0.25, 1.0, "brush_drop.volts", "carbon brushes: 0.3-1 V per pair"),
    "gear_back": (0.85, 0.949, "gear_efficiency.back (back-driving efficiency)",
                  "5 spur stages at 0.99 down to a lossy plastic first stage"),
    "inertia_factor": (0.8, 1.25, "rotor inertia x factor (log-uniform)", "the paper's Table 2 to two digits"),
    "r_factor": (0.9, 1.1, "winding resistance x factor (log-uniform)", "a 10 % tolerance of the wound resistance"),
}
LOG_UNIFORM = {"inertia_factor", "r_factor"}


def draw(rng: random.Random) -> dict[str, float]:
    out = {}
    for k, (lo, hi, _, _) in RANGES.items():
        out[k] = math.exp(rng.uniform(math.log(lo), math.log(hi))) if k in LOG_UNIFORM else rng.uniform(lo, hi)
    return out


def params_of(plant: PlantSpec, d: dict[str, float]) -> Any:
    p = plant.params({"motor_friction": {"coulomb_frac": d["coulomb_frac"], "static_frac": 1.4 * d["coulomb_frac"]},
                      "brush_drop": {"volts": d["brush_volts"]},
                      "gear_efficiency": {"back": d["gear_back"]}})
    axes = tuple(a.replace(rotor_inertia_kg_m2=a.rotor_inertia_kg_m2 * d["inertia_factor"],
                           resistance_ohm=a.resistance_ohm * d["r_factor"]) for a in p.axes)
    return replace(p, axes=axes)


@dataclass(frozen=True)
class Job:
    plant: PlantSpec
    index: int
    values: tuple[tuple[str, float], ...]
    freqs_hz: tuple[float, ...]
    settle: float | str = 0.3


def run_draw(job: Job) -> dict[str, Any]:
    t0 = time.process_time()
    d = dict(job.values)
    p = params_of(job.plant, d)
    out: dict[str, Any] = {"draw": job.index, "values": d, "axes": {}}
    for i, a in enumerate(p.axes):
        row = step5_on(CarriedBench(job.plant, a.name, Protocol(job.settle, "up"), params=p), job.freqs_hz)
        dz = None
        if row["freq_hz"] is not None:
            n = divider_for(row["freq_hz"], CLK_HZ, PWM_BITS)
            ramp = MotionRamp()
            dz = {}
            for direction in (1, -1):
                rec = record_motion_ramp(p, i, n, direction, ramp)
                try:
                    dz["forward" if direction > 0 else "reverse"] = motion_dead_zone(
                        *rec, threshold_counts=ramp.threshold_counts, freq_hz=model_waveform(n, 1).freq_hz,
                        direction=direction).pw0_pct
                except ValueError:
                    dz["forward" if direction > 0 else "reverse"] = None
        out["axes"][a.name] = {"freq_hz": row["freq_hz"], "kind": row["kind"], "dead_zone_pct": dz,
                               "message": row["message"]}
    out["cpu_s"] = time.process_time() - t0
    return out


def interval(v: Sequence[float]) -> dict[str, Any]:
    v = sorted(v)
    if not v:
        return {"n": 0}
    out: dict[str, Any] = {"n": len(v), "median": float(np.median(v)), "min": v[0], "max": v[-1]}
    if len(v) >= 10:
        out["p10"], out["p90"] = float(np.percentile(v, 10)), float(np.percentile(v, 90))
    return out


def run(plant: PlantSpec, draws: int, seed: int, freqs_hz: Sequence[float], settle: float | str = 0.3,
        engine: Engine = Engine(), say=print) -> dict[str, Any]:
    rng = random.Random(seed)
    jobs = [Job(plant, k, tuple(draw(rng).items()), tuple(freqs_hz), settle) for k in range(draws)]
    say(f"uncertainty: {draws} draws of the plant's parameters (Monte Carlo seed {seed}) on the {engine.name}")
    progress, res = Progress([1.0] * draws, engine.workers), []
    for k, (_, r) in enumerate(engine.map_unordered(run_draw, jobs), 1):
        res.append(r)
        say(f"uncertainty {k}/{draws}: " + ", ".join(f"{a} {v['freq_hz'] or 0:.4g} Hz" for a, v in r["axes"].items())
            + f" ({r['cpu_s']:.0f} s CPU; {progress.line(1.0, r['cpu_s'])})")
    res.sort(key=lambda r: r["draw"])
    axes = sorted({a for r in res for a in r["axes"]})
    summary = {}
    for a in axes:
        # a "nearest" point is no crossing: the curve missed the target over the whole grid
        f = [r["axes"][a]["freq_hz"] for r in res
             if r["axes"][a]["freq_hz"] is not None and r["axes"][a]["kind"] != "nearest"]
        dz = [min(x for x in r["axes"][a]["dead_zone_pct"].values() if x is not None) for r in res
              if r["axes"][a]["dead_zone_pct"] and any(x is not None for x in r["axes"][a]["dead_zone_pct"].values())]
        summary[a] = {"chosen_hz": interval(f), "dead_zone_pct": interval(dz), "no_choice": draws - len(f)}
    return {"kind": "parameter uncertainty: Monte Carlo over the stated ranges (not instrument noise)",
            "seed": seed, "draws": draws, "settle_s": settle, "freqs_hz": list(freqs_hz),
            "ranges": {k: {"low": lo, "high": hi, "applied_as": how, "why": why}
                       for k, (lo, hi, how, why) in RANGES.items()},
            "axes": summary, "runs": res, "cpu_s": sum(r["cpu_s"] for r in res)}


def markdown(doc: dict[str, Any]) -> list[str]:
    L = ["## The answer under the plant's parameter uncertainty", "",
         f"{doc['draws']} draws (Monte Carlo seed {doc['seed']}), each value uniform in its stated range, the method's "
         f"step 5 at a {doc['settle_s']} s settle on {len(doc['freqs_hz'])} carriers, the paper's dead zone at the chosen "
         "carrier. The interval is the spread the assumed ranges give (parameter uncertainty), not the "
         "instrument noise of the repeatability seeds.", "",
         "| parameter | range | applied as |", "|---|---|---|"]
    for k, r in doc["ranges"].items():
        L.append(f"| {k} | {r['low']:g} - {r['high']:g} | {r['applied_as']} ({r['why']}) |")
    L += ["", "| axis | chosen carrier: median [min, max] (Hz) | dead zone: median [min, max] (% duty) | draws with no "
          "crossing on the grid |", "|---|---|---|---|"]
    for a, v in doc["axes"].items():
        c, d = v["chosen_hz"], v["dead_zone_pct"]
        cs = "-" if not c.get("n") else f"{c['median']:.4g} [{c['min']:.4g}, {c['max']:.4g}]"
        ds = "-" if not d.get("n") else f"{d['median']:.2f} [{d['min']:.2f}, {d['max']:.2f}]"
        L.append(f"| {a} | {cs} | {ds} | {v['no_choice']} |")
    return L + [""]


@dataclass(frozen=True)
class UncertaintyPlan:
    draws: int = 10
    seed: int = 2026
    freqs_hz: tuple[float, ...] = (109.0, 235.0, 509.0, 1111.0, 2444.0, 5431.0)
    settle: float | str = 0.3
    quick: bool = False

    def key(self, plant: PlantSpec) -> str:
        return repr((plant.label, self.draws, self.seed, self.freqs_hz, self.settle))


FULL = UncertaintyPlan()
QUICK = UncertaintyPlan(draws=2, freqs_hz=(235.0, 1111.0, 5431.0), quick=True)


def study(plan: UncertaintyPlan, plant: PlantSpec, out_json: Path, digest: str, engine: Engine = Engine(),
          say=print) -> dict[str, Any]:
    """The Monte Carlo for ``plan``, reused from ``out_json`` while its inputs are unchanged."""
    from torqueloop.study.cache import cached

    return cached(out_json, digest, __file__, plan.key(plant),
                  lambda: run(plant, plan.draws, plan.seed, plan.freqs_hz, plan.settle, engine, say)
                  | {"quick": plan.quick}, say)
