# SPDX-License-Identifier: MIT
"""The experiment study (``make run``): the paper's experiment and its title
question (docs/experiment.md).

1. The characterisation of the experiment arm's plant (the lab's session on
   the simulated bench, pins from the RTL; :mod:`.characterization`), reused
   from build/characterize/ while its inputs are unchanged.
2. For P, PD and PID at T = 40 s: the **model arm** (the paper's simulation,
   `paper` plant), the **experiment arm** (the board image and the servo
   firmware in the loop on the `lab` plant, configured from the
   characterisation file as `torqueloop config load` does it) and the **fast
   path** with the same settings (the implementation check).
3. The experiment arm's cases on the fast path (:data:`CASES`): without PW0,
   at 20 kHz and at 50 Hz (carriers the method rejects).
4. The title question: a closed-loop sweep of the PWM carrier on the fast
   path, each carrier with its own dead zone and with PW0 off, PD and PID at
   T = 40 s from two start positions (4 carriers, 50 Hz - 24.4 kHz;
   ``--thorough``: 8 carriers, two step sizes, three starts), each run kept
   in build/characterize/sweep_runs/ while its inputs are unchanged.
5. One report in build/report/: report.md, report.json, PNGs.

An :class:`ExperimentPlan` says what to run; :func:`runs` turns it into
:class:`Run` objects (each one :class:`~torqueloop.sim.experiment.ExperimentConfig`
with the plants already parsed), which a process pool executes; the report
is written from the collected :class:`~torqueloop.sim.report.Study`.
"""

from __future__ import annotations

import json
import math
import os
import contextlib
import pickle
import sys
import time
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Union

from sim_models.variants import PlantSpec
from torqueloop.sim import experiment, native, report
from torqueloop.sim.experiment import ExperimentConfig, ModelRun, RtlRun
from torqueloop.spec.repo import REPO_ROOT
from torqueloop.study import answer, carrier_sweep, stability, table3, uncertainty
from torqueloop.study.characterization import inputs_digest, run_study
from torqueloop.study.engine import Engine, Progress, human_s

#: the thorough sweep's carriers (``--thorough``)
SWEEP_HZ = (50.0, 120.0, 300.0, 700.0, 1700.0, 4000.0, 10_000.0, 24_400.0)
#: make run's: the grid's ends and two between, about one carrier per factor 6-8 (docs/experiment.md, "The
#: sweep without the confound", says what this leaves out and why)
RUN_SWEEP_HZ = (50.0, 300.0, 1700.0, 24_400.0)
QUICK_SWEEP_HZ = (50.0, 1700.0, 24_400.0)
#: the sweep is also scored as if each run had ended here (carrier_sweep.t_check): whether T changes the answer
SHORT_T_S = 10.0
#: the experiment arm's cases on the fast path: name -> (what it is, the settings it changes)
CASES = {
    "pw0_off": ("no dead-zone compensation (PW0 = 0)", dict(pw0_off=True)),
    "reject_20khz": ("at 20 kHz, a carrier the method rejects", dict(pwm_hz=(20_000.0, 20_000.0))),
    "reject_50hz": ("at 50 Hz, the lowest of the sweep", dict(pwm_hz=(50.0, 50.0))),
}
LAWS = ("P", "PD", "PID")


@dataclass(frozen=True)
class ExperimentPlan:
    """What ``make run`` runs; :meth:`quick` is ``make run QUICK=1``."""

    t_end_s: float = 40.0                 # T of eq. (26)
    sweep_t_end_s: float = 40.0           # T of each sweep run
    laws: tuple[str, ...] = LAWS
    sweep_hz: tuple[float, ...] = RUN_SWEEP_HZ
    sweep_laws: tuple[str, ...] = ("PD", "PID")
    #: each sweep point's step sizes and start positions, in screw turns (a start away from 0 is reached by a
    #: move under the same law first, so the step begins from where, and the side from which, it arrived)
    sweep_steps_turns: tuple[float, ...] = (1.0,)
    sweep_starts_turns: tuple[float, ...] = (-0.5, 0.5)
    model_plant: PlantSpec = PlantSpec("paper")
    experiment_plant: PlantSpec = PlantSpec("lab")
    char_dir: Path = REPO_ROOT / "build" / "characterize"
    out: Path = REPO_ROOT / "build" / "report"
    jobs: int = field(default_factory=lambda: os.cpu_count() or 2)
    cluster: str | None = None            # a Dask scheduler's address (torqueloop/study/engine.py); None: local pool
    quick: bool = False

    @property
    def engine(self) -> Engine:
        return Engine(self.jobs, self.cluster)

    @classmethod
    def short(cls, **kw) -> "ExperimentPlan":
        """A first look in a few minutes: T = 2 s, a 3-carrier sweep of P at 1 s from one start."""
        return cls(**{"t_end_s": 2.0, "sweep_t_end_s": 1.0, "sweep_hz": QUICK_SWEEP_HZ, "sweep_laws": ("P",),
                      "sweep_starts_turns": (0.0,), "quick": True, **kw})

    @classmethod
    def thorough(cls, **kw) -> "ExperimentPlan":
        """The whole grid (``--thorough``, hours on 2 cores): 8 carriers, PD and PID at T = 40 s, two step
        sizes, three start positions."""
        return cls(**{"sweep_t_end_s": 40.0, "sweep_hz": SWEEP_HZ, "sweep_laws": ("PD", "PID"),
                      "sweep_steps_turns": (0.25, 1.0), "sweep_starts_turns": (0.0, -0.5, 0.5), **kw})

    def check(self) -> None:
        if self.t_end_s <= 0 or self.sweep_t_end_s <= 0:
            raise ValueError("--t-end and --sweep-t-end must be positive")
        if not self.laws or set(self.laws) - set(LAWS):
            raise ValueError(f"laws {self.laws}: choose from {', '.join(LAWS)}")

    @property
    def pin_source(self) -> str:
        """Where the characterisation's pins come from (quick: the cores' documented waveform)."""
        return "model" if self.quick else "rtl"


@dataclass(frozen=True)
class Run:
    """One job of the pool: ``kind`` rtl (the experiment arm and its
    implementation check), model (the model arm) or fast (a case or a sweep
    point); ``key`` says where its result goes in the :class:`~torqueloop.sim.report.Study`."""

    kind: str
    key: tuple
    config: ExperimentConfig

    def label(self) -> str:
        return f"{self.kind} {' '.join(map(str, self.key))}"


class RunFailed(str):
    """A run that raised: its one-line reason (the pool goes on with the rest)."""


Result = Union[RunFailed, ModelRun, tuple[RtlRun, ModelRun]]


#: the terminal while the simulators' output goes to the run's log (:func:`banners_to`)
_TERM = None


def _say(msg: str) -> None:
    print(f"[run] {msg}", file=_TERM or sys.stdout, flush=True)


@contextlib.contextmanager
def banners_to(log: Path):
    """Send everything written to stdout and stderr - the simulators' and
    make's banners, in this process and the pool's workers forked from it -
    to ``log``; :func:`_say`'s progress lines still reach the terminal."""
    global _TERM
    log.parent.mkdir(parents=True, exist_ok=True)
    sys.stdout.flush()
    sys.stderr.flush()
    saved = os.dup(1), os.dup(2)
    term = os.fdopen(os.dup(1), "w", buffering=1)
    with open(log, "ab") as fh:
        os.dup2(fh.fileno(), 1)
        os.dup2(fh.fileno(), 2)
    _TERM = term
    try:
        yield term
    finally:
        sys.stdout.flush()
        sys.stderr.flush()
        os.dup2(saved[0], 1)
        os.dup2(saved[1], 2)
        os.close(saved[0])
        os.close(saved[1])
        _TERM = None
        term.close()


def characterization(plan: ExperimentPlan) -> Path:
    """The experiment arm's characterisation file: reused while its inputs
    are unchanged, else the lab's session is run (pins from the RTL)."""
    plant, out = plan.experiment_plant, plan.char_dir
    cfg, digest_file = out / "characterization.json", out / "inputs.sha256"
    want = {inputs_digest(plant, s) for s in (("model", "rtl") if plan.quick else ("rtl",))}
    if cfg.exists() and digest_file.exists() and digest_file.read_text().strip() in want:
        _say(f"characterisation: {cfg.relative_to(REPO_ROOT) if cfg.is_relative_to(REPO_ROOT) else cfg} "
             f"is current (its inputs are unchanged); reused")
        return cfg
    _say(f"characterisation of the {plant.label} plant: the lab's session on the simulated bench "
         f"(pins from {plan.pin_source}) ...")
    rc = run_study(out, plant, seeds=1, source=plan.pin_source, ablation=False, linearity_freqs=())
    if rc != 0 or not cfg.exists():
        raise RuntimeError(f"the characterisation did not write a configuration (exit {rc}); see the log above")
    return cfg


def runs(plan: ExperimentPlan, char: Path, pw0_at: dict[float, tuple[int, int]] | None = None) -> list[Run]:
    """Every run of the plan, the long ones (RTL) first; ``pw0_at``: the
    sweep's PW0 per carrier (None: the characterisation file's at every carrier)."""
    base = ExperimentConfig(t_end_s=plan.t_end_s, progress=True)
    exp = replace(base, plant=plan.experiment_plant, char_config=str(char))
    out = [Run("rtl", (law,), replace(exp, law=law)) for law in plan.laws]
    for law in plan.laws:
        out.append(Run("model", (law,), replace(base, law=law, plant=plan.model_plant)))
        for name, (_, kw) in CASES.items():
            out.append(Run("fast", ("case", name, law), replace(exp, law=law, progress=False, **kw)))
    for f in plan.sweep_hz:
        for law in plan.sweep_laws:
            for pw0 in (True, False):
                for step in plan.sweep_steps_turns:
                    for start in plan.sweep_starts_turns:
                        s0 = round(start * experiment.COUNTS_PER_REV)
                        out.append(Run("fast", ("sweep", f, pw0, law, step, s0),
                                       replace(exp, law=law, t_end_s=plan.sweep_t_end_s, pwm_hz=(f, f),
                                               pw0_off=not pw0, pw0_counts=None if pw0_at is None else pw0_at[f],
                                               step_rad=step * 2 * math.pi, start_counts=(s0, s0),
                                               progress=False)))
    return out


#: a run's expected cost per simulated second, relative to the fast path's, for the
#: progress lines' estimate of the time left (measured side by side in one make run on
#: the 2-core machine, 2026-11-27: an RTL arm with its check 2 320 s for T = 40 s, a
#: fast-path case 46-53 s, the model arm 9-11 s)
COST_PER_SIM_S = {"rtl": 37.0, "fast": 1.0, "model": 0.2}


def cost(run: Run) -> float:
    """A run's expected cost (:data:`COST_PER_SIM_S` x its simulated time)."""
    return COST_PER_SIM_S[run.kind] * run.config.t_end_s


def split_cached(jobs: list[Run], cache: "carrier_sweep.RunCache") -> tuple[list[Run], list[tuple[Run, Result]]]:
    """The runs still to run, and the sweep runs ``cache`` already holds with their results."""
    todo, reused = [], []
    for j in jobs:
        r = cache.get(j.config) if j.kind == "fast" and j.key[0] == "sweep" else None
        if r is None:
            todo.append(j)
        else:
            reused.append((j, r))
    return todo, reused


def execute(run: Run) -> tuple[Run, Result, float]:
    """One run (in a pool worker): its result, or :class:`RunFailed` with the reason."""
    t0 = time.monotonic()
    cfg = run.config
    try:
        if run.kind == "rtl":   # and its implementation check: the fast path with the carriers' phase it met
            native.build()                # once per machine, keyed by its inputs (a cluster worker's first run)
            rtl = experiment.run_rtl(cfg, log=lambda m, **k: print(f"  {m.strip()}", flush=True))
            result: Result = (rtl, experiment.run_fast(replace(cfg, progress=False), rtl.carrier_start_clk))
        elif run.kind == "model":
            result = experiment.run_paper_model(cfg)
        else:
            result = experiment.run_fast(cfg)
    except Exception as e:   # noqa: BLE001 - reported by name, the other runs go on
        result = RunFailed(f"{type(e).__name__}: {e}")
    return run, result, time.monotonic() - t0


def collect(st: report.Study, run: Run, result: Result) -> None:
    """File one run's result where the report reads it."""
    if run.kind == "rtl":
        st.experiment_arm[run.key[0]], st.fast_check[run.key[0]] = result   # type: ignore[misc]
    elif run.kind == "model":
        st.model_arm[run.key[0]] = result                                     # type: ignore[assignment]
    elif run.key[0] == "case":
        st.cases.setdefault(run.key[1], {})[run.key[2]] = result              # type: ignore[assignment]
    else:
        cfg = run.config
        extra = {"target_rad": cfg.target_counts * 2 * math.pi / experiment.COUNTS_PER_REV}
        for i, ax in enumerate(("x", "z")):
            pw0 = 0 if cfg.pw0_off else cfg.pw0_counts[i] if cfg.pw0_counts is not None else cfg.board()[i]["PW0"]
            extra[ax] = {"pw0_counts": pw0, "start_counts": cfg.start_counts[i],
                         "step_counts": cfg.target_counts}
        st.sweep.append((run.key[1], run.key[2], run.key[3], result, extra))  # type: ignore[arg-type]


def run_experiment(plan: ExperimentPlan) -> int:
    """The whole study (module docstring); 0 when the report was written.
    The simulators' output goes to ``OUT/run.log``; the terminal gets one
    progress line per run."""
    plan.check()
    log = plan.out / "run.log"
    log.parent.mkdir(parents=True, exist_ok=True)
    log.write_text("")
    _say(f"the simulators' output (cocotb, Verilator, make) goes to {log}")
    with banners_to(log) as term:
        return _run_experiment(plan, term)


def _run_experiment(plan: ExperimentPlan, term) -> int:
    t0 = time.monotonic()
    char = characterization(plan)
    _say("building the board harness and the firmware ...")
    native.build()
    experiment.firmware_image()

    engine = plan.engine
    dz = carrier_sweep.dead_zones(plan.experiment_plant, plan.sweep_hz, plan.char_dir / "dead_zones.json",
                                  inputs_digest(plan.experiment_plant, "model"), engine, say=_say)
    every = runs(plan, char, dz["pw0"])
    st = report.Study(t_end_s=plan.t_end_s, target_rad=every[0].config.target_counts * 2 * math.pi / experiment.COUNTS_PER_REV,
                      laws=list(plan.laws), sweep_t_end_s=plan.sweep_t_end_s,
                      case_labels={k: v[0] for k, v in CASES.items()})
    cache = carrier_sweep.RunCache(plan.char_dir / "sweep_runs")
    jobs, reused = split_cached(every, cache)
    for run, result in reused:
        collect(st, run, result)
    n_sweep = sum(j.key[0] == "sweep" for j in every if j.kind == "fast")
    _say(f"{len(jobs)} runs on the {engine.name}: {len(plan.laws)} x experiment arm (RTL, T = {plan.t_end_s:g} s, "
         f"then its implementation check), model arm and {len(CASES)} cases per law, "
         f"{n_sweep - len(reused)} sweep runs (T = {plan.sweep_t_end_s:g} s; {len(reused)} more reused from "
         f"{cache.root.name}/, their inputs unchanged)")
    done, failed = 0, []
    progress = Progress([cost(j) for j in jobs], engine.workers)
    for _, (run, result, dt) in engine.map_unordered(execute, jobs):
        done += 1
        if isinstance(result, RunFailed):
            failed.append(f"{run.label()}: {result}")
            _say(f"{done}/{len(jobs)} {run.label()} FAILED after {dt:.0f} s: {result}")
            continue
        left = progress.done(cost(run), dt)
        _say(f"{done}/{len(jobs)} {run.label()} ({human_s(dt)}; {human_s(time.monotonic() - t0)} so far, "
             f"about {human_s(left)} left in this stage)")
        if run.key[0] == "sweep":
            cache.put(run.config, result)
        collect(st, run, result)
    if failed:
        for f in failed:
            _say(f)
        _say(f"{len(failed)} of {len(jobs)} runs failed; no report written")
        return 1
    st.sweep.sort(key=lambda r: (r[0], not r[1], r[2], r[4]["x"]["step_counts"], r[4]["x"]["start_counts"]))
    cfgdoc = json.loads(char.read_text())
    st.characterization = {
        "config": str(char.relative_to(REPO_ROOT) if char.is_relative_to(REPO_ROOT) else char),
        "source": f"plant {plan.experiment_plant.label}, simulated bench",
        "axes": {k: {f: v[f] for f in ("pwm_freq_hz", "achieved_hz", "pw0_counts", "tau_max_nm", "count_max")}
                 for k, v in cfgdoc["axes"].items()},
        "plots": [str(p) for p in sorted((plan.char_dir / "plots").glob("*.png"))],
    }
    stab = stability.study(stability.QUICK if plan.quick else stability.FULL, plan.experiment_plant,
                           plan.char_dir / ("stability_quick.json" if plan.quick else "stability.json"),
                           inputs_digest(plan.experiment_plant, "model"), engine, say=_say)
    st.characterization["stability"] = stability.summary_rows(stab)
    st.characterization["stability_verdict"] = {"axes": stab["verdict"], "quick": stab["quick"]}
    dec = table3.study(plan.experiment_plant, plan.laws, plan.t_end_s,
                       plan.char_dir / ("table3_decomposition_quick.json" if plan.quick else "table3_decomposition.json"),
                       inputs_digest(plan.experiment_plant, "model"), engine, say=_say, char_config=str(char))
    unc = uncertainty.study(uncertainty.QUICK if plan.quick else uncertainty.FULL, plan.experiment_plant,
                            plan.char_dir / ("uncertainty_quick.json" if plan.quick else "uncertainty.json"),
                            inputs_digest(plan.experiment_plant, "model"), engine, say=_say)
    st.meta = {"model_plant": plan.model_plant.label, "experiment_plant": plan.experiment_plant.label,
               "quick": plan.quick, "jobs": plan.jobs, "engine": engine.name, "wall_s_total": round(time.monotonic() - t0, 1)}
    plan.out.mkdir(parents=True, exist_ok=True)
    (plan.out / "data").mkdir(exist_ok=True)
    with open(plan.out / "data" / "runs.pkl", "wb") as fh:      # for re-scoring without re-simulating
        pickle.dump(st, fh)
    report.write(st, plan.out)
    quick = None if not plan.quick else {"T": plan.t_end_s, "n": len(plan.sweep_hz), "laws": "/".join(plan.sweep_laws),
                                         "Ts": plan.sweep_t_end_s, "nf": len(stability.QUICK.freqs_hz),
                                         "np": len(stability.QUICK.settles) * len(stability.QUICK.orders)}
    tc = None
    if plan.sweep_t_end_s > SHORT_T_S:
        short = carrier_sweep.short_rows(st.sweep, SHORT_T_S, st.target_rad)
        tc = carrier_sweep.t_check(json.loads((plan.out / "report.json").read_text())["sweep"], short,
                                   plan.sweep_t_end_s, SHORT_T_S)
    answer.finish(plan.out, quick, stab, json.loads((plan.out / "report.json").read_text())["sweep"], dz, unc, dec,
                  t_check=tc)
    print((plan.out / "report.md").read_text(), file=term)
    _say(f"report: {plan.out}/report.md, report.json, PNGs ({time.monotonic() - t0:.0f} s)")
    return 0
