# SPDX-License-Identifier: MIT
"""Does the characterisation's answer survive the bench protocol?  Step 5
(the chosen carrier) and the paper's dead zone at that carrier, per axis,
under each bench protocol: the settle before a reading (fixed 0.3 s, 1 s,
3 s, 10 s, or until the reading has converged) and the order the carriers are swept in
(up, down, shuffled with a printed seed).

The sweep order matters only if one reading leaves something behind for the
next.  On the simulated rope bench every reading starts from rest, so the
study carries what a real bench carries: the winding's temperature (the
plant's ``winding_thermal`` effect).  Each reading starts at the temperature
the previous one ended at, cooled for ``pause_s`` with the motor off while
the operator writes it down (the first-order model's own time constant).
With ``winding_thermal`` switched off the order cannot matter, and the
table shows it.

The dead zone is the paper's (raise the pulse until the stage moves, lower
it until it stops: :func:`torqueloop.characterize.simbench.motion_dead_zones`)
at the board carrier each protocol chose; it is measured on the stage axis,
not on the rope bench, so a protocol moves it only through the carrier it
chose.

Every (axis, protocol) is one job of :class:`~torqueloop.study.engine.Engine`.
Rows (``stability[]`` in results.json and report.json, docs/characterization.md):
``{axis, settle_s, order, seed, freq_hz, board_hz, kind, crossings_hz,
dead_zone_pct: {forward, reverse}, readings: [...], cpu_s}``; ``settle_s`` is
a number or ``"converged"``.
"""

from __future__ import annotations

import math
import random
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Sequence

import numpy as np

from sim_models.variants import PlantSpec
from torqueloop.characterize.config import CLK_HZ, PWM_BITS
from torqueloop.characterize.data import BenchConstants, Sweep
from torqueloop.characterize.method import MethodError, Thresholds, step5_candidates
from torqueloop.characterize.simbench import model_waveform, motion_dead_zones, rope_config
from torqueloop.spec.pwm import carrier_hz, divider_for, full_scale
from torqueloop.study.engine import Engine, Progress

#: the carriers of the stability sweeps: the range where the settle rules put
#: the crossings (docs/plant.md, "Chosen carrier against the settle rule": z near 200 Hz at a
#: 0.3 s settle, x up to 5.8 kHz converged); the
#: sweep's ends (50 Hz, 24.4 kHz) are left out: no protocol crosses there, and
#: a converged reading at 24.4 kHz costs minutes of CPU
FREQS_HZ = (109.0, 235.0, 509.0, 1111.0, 2444.0, 5431.0)
QUICK_FREQS_HZ = (235.0, 1111.0, 5431.0)
SETTLES: tuple[float | str, ...] = (0.3, 1.0, 3.0, 10.0, "converged")
ORDERS = ("up", "down", "shuffled")


@dataclass(frozen=True)
class Protocol:
    """How the bench takes its readings."""

    settle: float | str                 # seconds held before a reading, or "converged"
    order: str = "up"                   # up | down | shuffled
    seed: int = 0                       # the shuffle's seed
    pause_s: float = 5.0                # motor off between two readings (the winding cools)
    max_settle_s: float = 20.0          # the converged rule's limit

    def __post_init__(self) -> None:
        if self.order not in ORDERS:
            raise ValueError(f"order {self.order!r}: one of {', '.join(ORDERS)}")
        rope_config(self.settle)        # refuses a bad settle

    def sequence(self, freqs: Sequence[float]) -> list[float]:
        f = sorted(freqs)
        if self.order == "down":
            return f[::-1]
        if self.order == "shuffled":
            random.Random(self.seed).shuffle(f)
        return f

    @property
    def label(self) -> str:
        s = "converged" if self.settle == "converged" else f"{self.settle:g} s"
        return f"settle {s}, order {self.order}" + (f" (seed {self.seed})" if self.order == "shuffled" else "")


class CarriedBench:
    """The plant's rope dynamometer for one axis, each reading starting from
    the winding temperature the previous one left (cooled over the pause)."""

    def __init__(self, plant: PlantSpec, axis: str, protocol: Protocol, params: Any = None) -> None:
        from sim_models.dyno import RopeDynamometer

        p = params if params is not None else plant.params()
        names = [a.name for a in p.axes]
        if axis not in names:
            raise ValueError(f"axis {axis!r}: the plant has {names}")
        self.axis = p.axes[names.index(axis)]
        cfg = rope_config(protocol.settle, **({"max_settle_s": protocol.max_settle_s}
                                              if protocol.settle == "converged" else {}))
        self.dyno = RopeDynamometer(self.axis, p, cfg)
        self.protocol = protocol
        self.theta_K = 0.0
        self._fa: Any = None
        make = self.dyno._make

        def _make() -> Any:
            fa = make()
            fa.theta = self.theta_K     # R(T) is rebuilt from it at the first step
            self._fa = fa
            return fa

        self.dyno._make = _make
        self.torque_per_n = self.dyno.torque_per_newton()
        self.supply_v = p.bridge.supply_V
        self.wheel_radius_m = cfg.wheel_radius_m
        self.theta_deg = cfg.rope_angle_deg

    def reading(self, count_max: int, duty_counts: int) -> dict[str, Any]:
        w = model_waveform(count_max, duty_counts)
        start = self.theta_K
        self.dyno._cache.clear()        # the same setting at another temperature is another reading
        tr = self.dyno.trace(w.segments, w.period_s)
        end = float(self._fa.theta) if self.axis.heats else 0.0
        self.theta_K = end * math.exp(-self.protocol.pause_s / self.axis.winding_thermal_tau_s) if self.axis.heats else 0.0
        return {"freq_hz": w.freq_hz, "duty_counts": duty_counts, "torque_nm": tr.force_mean_N * self.torque_per_n,
                "settle_s": tr.settle_s, "converged": tr.converged, "theta_start_K": start, "theta_end_K": end}


@dataclass(frozen=True)
class Job:
    plant: PlantSpec
    axis: str
    protocol: Protocol
    freqs_hz: tuple[float, ...]
    dead_zone: bool = True


def run_job(job: Job) -> dict[str, Any]:
    """Step 2 (stall), the 50 % sweep in the protocol's order, step 5, and the
    paper's dead zone at the chosen board carrier."""
    t0 = time.process_time()
    row = step5_on(CarriedBench(job.plant, job.axis, job.protocol), job.freqs_hz)
    row.update(axis=job.axis, plant=job.plant.label)
    if job.dead_zone and row["freq_hz"] is not None:
        dz = motion_dead_zones(job.plant, [row["freq_hz"]], axes=(job.axis,))
        row["dead_zone_pct"] = {("forward" if d.direction > 0 else "reverse"): d.pw0_pct for d in dz}
    row["cpu_s"] = time.process_time() - t0
    return row


def step5_on(b: CarriedBench, freqs_hz: Sequence[float]) -> dict[str, Any]:
    """Step 2 (stall), the 50 % sweep in the bench's protocol's order, step 5."""
    pr = b.protocol
    axis = b.axis.name
    m = full_scale(PWM_BITS)
    half = (m + 1) // 2
    stall = b.reading(divider_for(freqs_hz[0], CLK_HZ, PWM_BITS), m)
    rd = [b.reading(divider_for(f, CLK_HZ, PWM_BITS), half) for f in pr.sequence(freqs_hz)]
    by_f = sorted(rd, key=lambda r: r["freq_hz"])
    target = stall["torque_nm"] * half / m
    sweep = Sweep("frequency", axis, BenchConstants(b.wheel_radius_m, b.theta_deg, b.supply_v),
                  x=np.array([r["freq_hz"] for r in by_f]), torque_nm=np.array([r["torque_nm"] for r in by_f]),
                  current_a=np.zeros(len(by_f)), duty_pct=100.0 * half / m,
                  stall_torque_nm=stall["torque_nm"], stall_current_a=0.0, force_given=True)
    row: dict[str, Any] = {"axis": axis, "settle_s": pr.settle, "order": pr.order,
                           "seed": pr.seed if pr.order == "shuffled" else None, "pause_s": pr.pause_s,
                           "tau_max_nm": stall["torque_nm"],
                           "readings": [{**r, "rel_to_target_pct": 100.0 * (r["torque_nm"] / target - 1.0)} for r in rd],
                           "freq_hz": None, "board_hz": None, "kind": None, "crossings_hz": [],
                           "dead_zone_pct": None, "message": ""}
    try:
        s5 = step5_candidates(sweep, Thresholds())
        c = s5.candidates[0]
        row.update(freq_hz=c.freq_hz, kind=c.kind, message=s5.message,
                   crossings_hz=[x.freq_hz for x in s5.candidates if x.kind == "crossing"],
                   board_hz=carrier_hz(divider_for(c.freq_hz, CLK_HZ, PWM_BITS), CLK_HZ, PWM_BITS))
    except MethodError as e:
        row["message"] = str(e).split(": ", 1)[-1]
    return row


def protocols(settles: Sequence[float | str] = SETTLES, orders: Sequence[str] = ORDERS,
              seed: int = 0, converged_orders: Sequence[str] | None = None) -> list[Protocol]:
    """Every settle with every order (``converged_orders``: the orders for
    the converged rule, whose readings cost up to ``max_settle_s`` each)."""
    return [Protocol(s, o, seed) for s in settles
            for o in (orders if s != "converged" or converged_orders is None else converged_orders)]


def run(plant: PlantSpec, axes: Sequence[str] = ("x", "z"), settles: Sequence[float | str] = SETTLES,
        orders: Sequence[str] = ORDERS, freqs_hz: Sequence[float] = FREQS_HZ, seed: int = 0,
        engine: Engine = Engine(), say=print, converged_orders: Sequence[str] | None = None,
        dead_zone: bool = True) -> list[dict[str, Any]]:
    """Every (axis, protocol) on the engine; rows in a fixed order (``dead_zone``
    False: the chosen carrier only, without the motion threshold at it)."""
    jobs = [Job(plant, a, p, tuple(freqs_hz), dead_zone) for a in axes
            for p in protocols(settles, orders, seed, converged_orders)]
    order = sorted(jobs, key=_cost, reverse=True)   # the longest first: no long job left alone at the end
    say(f"stability: {len(jobs)} sweeps ({len(freqs_hz)} carriers each, plant {plant.label}; "
        f"shuffled order's seed {seed}) on the {engine.name}")
    progress, rows = Progress([_cost(j) for j in jobs], engine.workers), {}
    for k, (job, row) in enumerate(engine.map_unordered(run_job, order), 1):
        rows[(job.axis, job.protocol)] = row
        say(f"stability {k}/{len(jobs)} axis {job.axis}, {job.protocol.label}: chosen {_hz(row['freq_hz'])} "
            f"({row['cpu_s']:.0f} s CPU; {progress.line(_cost(job), row['cpu_s'])})")
    return [rows[(j.axis, j.protocol)] for j in jobs]


def _cost(job: Job) -> float:
    """A job's expected cost, for the order the engine takes them in: the
    simulated time it holds (the converged rule's readings up to
    ``max_settle_s`` each; a stall reading and one per carrier)."""
    s = job.protocol.settle
    return (job.protocol.max_settle_s if s == "converged" else float(s)) * (len(job.freqs_hz) + 1)


def _hz(v: float | None) -> str:
    return "none" if v is None else f"{v:.4g} Hz"


def verdict(rows: Sequence[dict[str, Any]], tol_frac: float = 0.25) -> dict[str, Any]:
    """Per axis: the chosen carriers' span over the protocols, and whether
    the choice survives them (every protocol found a crossing or an
    on-target point - a "nearest" point is none - all within ``tol_frac``
    of their median, on a log scale: a factor 1.25 either way)."""
    out: dict[str, Any] = {}
    for a in sorted({r["axis"] for r in rows}):
        rr = [r for r in rows if r["axis"] == a]
        # a "nearest" point is no crossing: the curve missed the target over the whole grid
        f = [r["freq_hz"] for r in rr if r["freq_hz"] is not None and r.get("kind", "crossing") != "nearest"]
        if not f:
            out[a] = {"stable": False, "min_hz": None, "max_hz": None, "median_hz": None, "n": len(rr), "chosen": 0}
            continue
        med = float(np.exp(np.median(np.log(f))))
        ok = len(f) == len(rr) and all(abs(math.log(x / med)) <= math.log(1 + tol_frac) for x in f)
        by_settle: dict[str, list[float]] = {}
        for r in rr:
            if r["freq_hz"] is not None:
                by_settle.setdefault(str(r["settle_s"]), []).append(r["freq_hz"])
        out[a] = {"stable": ok, "min_hz": min(f), "max_hz": max(f), "median_hz": med, "n": len(rr),
                  "chosen": len(f), "tolerance_factor": 1 + tol_frac,
                  "order_span_by_settle": {s: [min(v), max(v)] for s, v in by_settle.items()}}
    return out


def markdown(rows: Sequence[dict[str, Any]], ver: dict[str, Any]) -> list[str]:
    L = ["## Does the chosen carrier survive the bench protocol?", "",
         "Step 5 on the simulated rope bench under each protocol (settle before a reading; order of the sweep, "
         "each reading starting at the winding temperature the previous one left), and the paper's dead zone "
         "(motion threshold: the duty below which the stage stops) at the board carrier each protocol chose.", "",
         "| axis | settle | order | chosen (Hz) | on the board (Hz) | dead zone fwd / rev (% duty) | "
         "readings converged | winding at the end (K) | CPU (s) |", "|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        dz = r["dead_zone_pct"]
        conv = sum(x["converged"] for x in r["readings"])
        s = r["settle_s"] if r["settle_s"] == "converged" else f"{r['settle_s']:g} s"
        o = r["order"] + (f" (seed {r['seed']})" if r["seed"] is not None else "")
        dzs = "-" if dz is None else " / ".join(_fmt(dz.get(k), ".2f") for k in ("forward", "reverse"))
        ch = (f"none (nearest {_fmt(r['freq_hz'])})" if r.get("kind") == "nearest" else _fmt(r["freq_hz"]))
        L.append(f"| {r['axis']} | {s} | {o} | {ch} | {_fmt(r['board_hz'])} | {dzs} | "
                 f"{conv}/{len(r['readings'])} | {r['readings'][-1]['theta_end_K']:.1f} | {r['cpu_s']:.0f} |")
    L += [""] + pivot(rows) + [""]
    for a, v in ver.items():
        if v["median_hz"] is None:
            L.append(f"- Axis {a}: no protocol gave a step-5 carrier.")
            continue
        L.append(f"- Axis {a}: the chosen carrier spans {v['min_hz']:.4g}-{v['max_hz']:.4g} Hz over {v['n']} protocols "
                 f"({v['chosen']} chose one). "
                 + ("It survives them: every protocol chose within a factor "
                    f"{v['tolerance_factor']:g} of {v['median_hz']:.4g} Hz." if v["stable"] else
                    f"It does not survive them: the bench protocol decides it, and this study names no carrier "
                    f"for axis {a}."))
    return L + [""]


def pivot(rows: Sequence[dict[str, Any]]) -> list[str]:
    """The chosen carrier against the settle (rows) and the sweep order
    (columns), both axes: "none" where step 5 found no crossing or
    on-target point (its "nearest" point is no choice)."""
    orders = [o for o in ORDERS if any(r["order"] == o for r in rows)]
    settles: list[Any] = []
    for r in rows:
        if r["settle_s"] not in settles:
            settles.append(r["settle_s"])
    L = ["Chosen carrier (Hz) against the settle and the sweep order:", "",
         "| axis | settle | " + " | ".join(orders) + " |", "|---|---|" + "---|" * len(orders)]
    for a in sorted({r["axis"] for r in rows}):
        for s in settles:
            cells = []
            for o in orders:
                rr = [r for r in rows if r["axis"] == a and r["settle_s"] == s and r["order"] == o]
                if not rr:
                    cells.append("not run")
                elif rr[0]["freq_hz"] is None or rr[0].get("kind") == "nearest":
                    cells.append("none")
                else:
                    cells.append(format(rr[0]["freq_hz"], ".4g"))
            lab = s if s == "converged" else f"{s:g} s"
            L.append(f"| {a} | {lab} | " + " | ".join(cells) + " |")
    return L


def _fmt(v: float | None, spec: str = ".4g") -> str:
    return "-" if v is None else format(v, spec)


@dataclass(frozen=True)
class StabilityPlan:
    """Which protocols and carriers: :data:`FULL` for ``make characterize``
    and ``make run``, :data:`QUICK` for ``make run QUICK=1`` (too few
    protocols and carriers to answer; it shows the table's shape)."""

    settles: tuple[float | str, ...] = SETTLES
    orders: tuple[str, ...] = ORDERS
    freqs_hz: tuple[float, ...] = FREQS_HZ
    seed: int = 0
    converged_orders: tuple[str, ...] = ("up", "down")
    quick: bool = False

    def key(self, plant: PlantSpec) -> str:
        return repr((plant.label, self.settles, self.orders, self.freqs_hz, self.seed, self.converged_orders))


FULL = StabilityPlan()
QUICK = StabilityPlan(settles=(0.3, 1.0), orders=("up", "down"), freqs_hz=QUICK_FREQS_HZ, quick=True)


def study(plan: StabilityPlan, plant: PlantSpec, out_json: Path, digest: str, engine: Engine = Engine(),
          say=print) -> dict[str, Any]:
    """The table for ``plan``, reused from ``out_json`` while the inputs'
    digest (the plant, the bench, the method: characterization.inputs_digest)
    and the plan are unchanged."""
    from torqueloop.study.cache import cached

    def compute() -> dict[str, Any]:
        t0 = time.monotonic()
        rows = run(plant, settles=plan.settles, orders=plan.orders, freqs_hz=plan.freqs_hz, seed=plan.seed,
                   engine=engine, say=say, converged_orders=plan.converged_orders)
        return {"quick": plan.quick, "rows": rows, "verdict": verdict(rows),
                "cpu_s": sum(r["cpu_s"] for r in rows), "wall_s": time.monotonic() - t0}

    return cached(out_json, digest, __file__, plan.key(plant), compute, say)


def summary_rows(doc: dict[str, Any]) -> list[dict[str, Any]]:
    """The report's ``characterization.stability[]``: one row per (axis,
    protocol) without the per-reading detail."""
    keep = ("axis", "settle_s", "order", "seed", "freq_hz", "board_hz", "kind", "crossings_hz", "dead_zone_pct",
            "tau_max_nm", "cpu_s")
    return [{k: r[k] for k in keep} | {"readings_converged": sum(x["converged"] for x in r["readings"]),
                                       "readings": len(r["readings"])} for r in doc["rows"]]
