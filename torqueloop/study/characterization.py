# SPDX-License-Identifier: MIT
"""The characterisation study: the method on the simulated lab bench
(``torqueloop-study characterize sim``, ``make characterize``).

1. **The lab's session** (instrument seed 0): the sweeps as CSV files in
   ``OUT/data/<axis>/``, then exactly what ``torqueloop-study characterize run`` does with
   them (:func:`torqueloop.characterize.conclude.conclude`): the configuration ``OUT/characterization.json`` (what the board's
   ``torqueloop config load`` and the experiment load) and the Fig. 10/11
   analogues in ``OUT/plots/``.
2. **Repeatability**: the same session with seeds 1..N-1 (other gauge and
   ammeter noise; the physics of a setting is simulated once): the chosen
   frequency and PW0 per seed, their median and range.
3. **Linearity across frequency**: duty sweeps at several frequencies
   besides the chosen one, judged by steps 6-7 (R^2, worst deviation, PW0).
4. **Which effect decides** (``--ablation``): the session again with each of
   the plant variant's effects switched off in turn.

``OUT/results.json`` (keys documented in docs/characterization.md) and
``OUT/results.md`` hold the numbers; ``OUT/plots/fig10_<axis>_effects.png``
overlays the 50 %-duty curves.
"""

from __future__ import annotations

import json
import math
import statistics
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Sequence

import numpy as np

from sim_models.variants import PlantSpec, effects_of
from torqueloop.characterize.conclude import conclude
from torqueloop.characterize.config import CLK_HZ, PWM_BITS
from torqueloop.characterize.data import read_sweep, write_sweep
from torqueloop.characterize.method import MotorResult, Thresholds, characterize_motor, steps67_linearity
from torqueloop.characterize.simbench import (LabBench, Waveforms, duty_settings, record_duty_sweep,
                                              record_frequency_sweep, simulate_lab)
from torqueloop.spec.pwm import carrier_hz, divider_for
from torqueloop.spec.repo import REPO_ROOT
from torqueloop.study import stability, uncertainty
from torqueloop.study.engine import Engine

#: extra duty sweeps of the study: the paper's range ends, its two optima, and the carriers above
LINEARITY_FREQS_HZ = (50.0, 200.0, 450.0, 2000.0, 24_400.0)


def inputs_digest(plant: PlantSpec, source: str) -> str:
    """A digest of everything the lab's session depends on (the plant, the
    bench, the method, this study, the PWM cores and eq. 4): make run reuses
    a written configuration whose digest still matches."""
    import hashlib

    files = sorted([*(REPO_ROOT / "sim_models").rglob("*.py"), *(REPO_ROOT / "sim_models" / "params").glob("*.toml"),
                    *(REPO_ROOT / "torqueloop" / "characterize").glob("*.py"), Path(__file__).resolve(),
                    *(REPO_ROOT / "torqueloop" / "characterize").glob("*.v"),
                    REPO_ROOT / "torqueloop" / "spec" / "pwm.py", REPO_ROOT / "torqueloop" / "spec" / "system.toml",
                    REPO_ROOT / "rtl" / "motion" / "tl_freq_div.v", REPO_ROOT / "rtl" / "motion" / "tl_pwm_torque.v"])
    h = hashlib.sha256(f"{plant.label}|{source}".encode())
    for f in files:
        h.update(str(f.relative_to(REPO_ROOT)).encode())
        h.update(f.read_bytes())
    return h.hexdigest()


def _say(msg: str) -> None:
    print(f"[characterize] {msg}", flush=True)


@dataclass
class AxisStudy:
    name: str
    sessions: list[MotorResult] = field(default_factory=list)   # index = seed
    linearity: list[dict[str, Any]] = field(default_factory=list)
    ablation: dict[str, dict[str, Any]] = field(default_factory=dict)


def _outcome(r: MotorResult) -> dict[str, Any]:
    lin = r.linearity
    return {
        "status": r.status,
        "chosen_hz": None if r.chosen is None else r.chosen.freq_hz,
        "pw0_pct": None if lin is None else lin.pw0_pct,
        "r2": None if lin is None else lin.r2,
        "message": r.message,
    }


def _interval(values: Sequence[float | None]) -> dict[str, Any]:
    v = [x for x in values if x is not None]
    if not v:
        return {"n": 0, "median": None, "min": None, "max": None}
    return {"n": len(v), "median": statistics.median(v), "min": min(v), "max": max(v)}


def _relative_curve(r: MotorResult) -> tuple[np.ndarray, np.ndarray]:
    """The 50 % sweep in % of the step-5 target (tau_max x duty)."""
    fs = r.freq_sweep
    target = float(fs.stall_torque_nm) * float(fs.duty_pct) / 100.0
    return fs.x, 100.0 * (fs.torque_nm / target - 1.0)


def crossings(r: MotorResult) -> list[float]:
    """Every frequency where the 50 % curve crosses its target (interpolated in log f)."""
    f, rel = _relative_curve(r)
    out = []
    for k in range(len(f) - 1):
        a, b = rel[k], rel[k + 1]
        if a == 0:
            out.append(float(f[k]))
        elif a * b < 0:
            w = a / (a - b)
            out.append(float(math.exp(math.log(f[k]) + w * (math.log(f[k + 1]) - math.log(f[k])))))
    return out


def run_study(out: Path, plant: PlantSpec, seeds: int = 10, axes: Sequence[str] = ("x", "z"),
              source: str = "rtl", sim: str = "verilator", th: Thresholds = Thresholds(),
              ablation: bool = True, linearity_freqs: Sequence[float] = LINEARITY_FREQS_HZ,
              stability_plan: "stability.StabilityPlan | None" = None,
              uncertainty_plan: "uncertainty.UncertaintyPlan | None" = None, engine: Engine = Engine()) -> int:
    """The whole study (module docstring).  Returns the exit status of the
    lab's session (0: every axis passed and the configuration was written)."""
    t0 = time.monotonic()
    out.mkdir(parents=True, exist_ok=True)
    wf = Waveforms(source, sim)  # type: ignore[arg-type]
    bench = LabBench(plant)
    studies = {a: AxisStudy(a) for a in axes}

    # 1. the lab's session, then what `torqueloop-study characterize run` does with its files
    _say(f"plant {plant.label}, pins from {source}: the lab's session (seed 0)")
    first = simulate_lab(out / "data", bench, axes, seed=0, wf=wf, th=th)
    for a, r in first.items():
        studies[a].sessions.append(r)
    status = conclude(first, out / "data", out / "characterization.json", out / "plots", th)
    if status == 0:
        (out / "inputs.sha256").write_text(inputs_digest(plant, source) + "\n")

    # 1b. the chosen carrier under each bench protocol (pins: the cores' documented waveform)
    stab = None
    if stability_plan is not None:
        stab = stability.study(stability_plan, plant, out / "stability.json", inputs_digest(plant, "model"),
                               engine, say=_say)
    unc = None
    if uncertainty_plan is not None:
        unc = uncertainty.study(uncertainty_plan, plant, out / "uncertainty.json", inputs_digest(plant, "model"),
                                engine, say=_say)

    # 2. repeatability over the instrument noise; the duty sweeps the seeds
    # will ask for are captured first, in one RTL run
    _prefetch_duty_sweeps(wf, bench, axes, range(1, seeds), th, out / "seeds")
    for seed in range(1, seeds):
        rs = simulate_lab(out / "seeds" / f"seed{seed}", bench, axes, seed=seed, wf=wf, th=th, quiet=True)
        for a, r in rs.items():
            studies[a].sessions.append(r)
        _say(f"seed {seed}: " + ", ".join(f"{a} {_brief(r)}" for a, r in rs.items()))

    # 3. linearity at other frequencies (seed 0's instruments)
    wf.get([s for a in axes for f in linearity_freqs for s in duty_settings(bench.plan, f)])
    for a in axes:
        st = studies[a]
        tau_max = float(st.sessions[0].freq_sweep.stall_torque_nm)
        chosen = st.sessions[0].chosen
        freqs = sorted({*linearity_freqs, *([chosen.freq_hz] if chosen and linearity_freqs else [])})
        for f in freqs:
            ds = record_duty_sweep(bench.measure(a, 0), bench.plan, a, f, wf)
            lin = steps67_linearity(ds, tau_max, th)
            st.linearity.append({"freq_hz": ds.freq_hz, "r2": lin.r2, "worst_dev_frac": lin.worst_dev_frac,
                                 "pw0_pct": lin.pw0_pct, "passes_step7": lin.ok})
        _say(f"{a}: linearity at " + ", ".join(f"{d['freq_hz']:.4g} Hz R^2 {d['r2']:.4f}" for d in st.linearity))

    # 4. each effect off in turn
    if ablation:
        for eff in effects_of(plant.name):
            if eff in plant.off:
                continue
            p2 = plant.without(eff)
            rs = simulate_lab(out / "ablation" / p2.label, LabBench(p2), axes, seed=0, wf=wf, th=th, quiet=True)
            for a, r in rs.items():
                studies[a].ablation[eff] = {**_outcome(r), "crossings_hz": crossings(r),
                                            "curve_rel_pct": _relative_curve(r)[1].tolist()}
            _say(f"{eff} off: " + ", ".join(f"{a} {_brief(r)}" for a, r in rs.items()))

    doc = _results(plant, seeds, source, bench, studies, time.monotonic() - t0)
    md = _markdown(doc)
    if stab is not None:
        doc["stability"] = stability.summary_rows(stab)
        doc["stability_verdict"] = stab["verdict"]
        md += "\n" + "\n".join(stability.markdown(stab["rows"], stab["verdict"]))
    if unc is not None:
        doc["uncertainty"] = {k: v for k, v in unc.items() if k != "runs"}
        doc["uncertainty"]["instrument_noise"] = {a: {"chosen_hz": d["chosen_hz"], "pw0_pct": d["pw0_pct"]}
                                                  for a, d in doc["axes"].items()}
        md += "\n" + "\n".join(uncertainty.markdown(unc))
    (out / "results.json").write_text(json.dumps(doc, indent=2, sort_keys=True, default=float) + "\n")
    (out / "results.md").write_text(md)
    _plot_effects(out / "plots", studies)
    _say(f"wrote {out / 'results.json'}, {out / 'results.md'} ({doc['wall_s']:.0f} s)")
    return status


def _prefetch_duty_sweeps(wf: Waveforms, bench: LabBench, axes: Sequence[str], seeds: Sequence[int],
                          th: Thresholds, tmp: Path) -> None:
    """The first duty sweep each seed's session will ask for (its frequency
    sweep and step 5, from cached physics), captured in one batch: a pin
    capture from the RTL costs a simulator start-up, so one start for all
    seeds instead of one per new frequency.  A session that asks for more
    (step 7 failing) captures the rest itself."""
    want: list[tuple[int, int]] = []
    for seed in seeds:
        for a in axes:
            fs = record_frequency_sweep(bench.measure(a, seed), bench.plan, a, wf)
            path = tmp / f"prefetch_{a}_{seed}.csv"
            path.parent.mkdir(parents=True, exist_ok=True)
            write_sweep(path, fs)                     # the method reads what the session's file holds
            r = characterize_motor(read_sweep(path), [], th)
            if r.status == "need_duty_sweep" and r.next_freq_hz is not None:
                want += duty_settings(bench.plan, r.next_freq_hz)
    wf.get(want)


def _brief(r: MotorResult) -> str:
    if r.status != "pass":
        return r.status
    return f"{r.chosen.freq_hz:.4g} Hz, PW0 {r.linearity.pw0_pct:.2f} %"  # type: ignore[union-attr]


def _results(plant: PlantSpec, seeds: int, source: str, bench: LabBench, studies: dict[str, AxisStudy],
             wall_s: float) -> dict[str, Any]:
    axes: dict[str, Any] = {}
    for a, st in studies.items():
        s0 = st.sessions[0]
        f, rel = _relative_curve(s0)
        per_seed = [_outcome(r) for r in st.sessions]
        chosen = [o["chosen_hz"] for o in per_seed]
        axes[a] = {
            "tau_max_nm": float(s0.freq_sweep.stall_torque_nm),
            "sweep": [{"freq_hz": float(x), "torque_nm": float(t), "rel_to_target_pct": float(r)}
                      for x, t, r in zip(f, s0.freq_sweep.torque_nm, rel)],
            "crossings_hz": crossings(s0),
            "session": _outcome(s0),
            "seeds": per_seed,
            "chosen_hz": _interval(chosen),
            "chosen_board_hz": _interval([None if c is None else carrier_hz(divider_for(c)) for c in chosen]),
            "pw0_pct": _interval([o["pw0_pct"] for o in per_seed]),
            "linearity": st.linearity,
            "ablation": st.ablation,
        }
    cfg = bench.config
    return {
        "schema": "torqueloop-characterization-study", "schema_version": 1,
        "plant": plant.label, "seeds": seeds, "pin_source": source,
        "bench": {"wheel_radius_m": cfg.wheel_radius_m, "rope_N_per_m": cfg.rope_N_per_m,
                  "rope_N_s_per_m": cfg.rope_N_s_per_m, "wheel_inertia_kg_m2": cfg.wheel_inertia_kg_m2,
                  "ramp_s": cfg.ramp_s, "settle_s": cfg.settle_s, "window_s": cfg.window_s,
                  "gauge": vars(cfg.gauge), "ammeter": vars(cfg.ammeter)},
        "clk_hz": CLK_HZ, "pwm_bits": PWM_BITS,
        "axes": axes,
        "wall_s": wall_s,
    }


def _fmt(v: Any, spec: str = ".4g") -> str:
    return "-" if v is None else format(v, spec)


def _markdown(doc: dict[str, Any]) -> str:
    L = [f"# Characterisation on the simulated bench: plant `{doc['plant']}`", "",
         f"Pins from {doc['pin_source']}; {doc['seeds']} instrument seeds; wall time {doc['wall_s']:.0f} s.", "",
         "| axis | tau_max (N m) | 50 % curve crosses tau_max/2 at (Hz) | chosen (seed 0) | chosen, median [min, max] over seeds | "
         "PW0 %, median [min, max] | status (seeds passing) |", "|---|---|---|---|---|---|---|"]
    for a, d in doc["axes"].items():
        c, p = d["chosen_hz"], d["pw0_pct"]
        npass = sum(1 for s in d["seeds"] if s["status"] == "pass")
        L.append(f"| {a} | {d['tau_max_nm']:.4g} | {', '.join(f'{x:.4g}' for x in d['crossings_hz']) or 'none'} | "
                 f"{_fmt(d['session']['chosen_hz'])} Hz | {_fmt(c['median'])} [{_fmt(c['min'])}, {_fmt(c['max'])}] Hz | "
                 f"{_fmt(p['median'], '.2f')} [{_fmt(p['min'], '.2f')}, {_fmt(p['max'], '.2f')}] | "
                 f"{d['session']['status']} ({npass}/{len(d['seeds'])}) |")
    for a, d in doc["axes"].items():
        L += ["", f"## Axis {a}: torque at 50 % duty against its target (seed 0)", "",
              "| f (Hz) | " + " | ".join(f"{s['freq_hz']:.4g}" for s in d["sweep"]) + " |",
              "|---|" + "---|" * len(d["sweep"]),
              "| % of target | " + " | ".join(f"{s['rel_to_target_pct']:+.1f}" for s in d["sweep"]) + " |"]
        L += ["", f"Steps 6-7 at other frequencies (axis {a}):", "", "| f (Hz) | R^2 | worst deviation (% of tau_max) | PW0 (%) | step 7 |",
              "|---|---|---|---|---|"]
        for s in d["linearity"]:
            L.append(f"| {s['freq_hz']:.4g} | {s['r2']:.4f} | {100 * s['worst_dev_frac']:.2f} | {s['pw0_pct']:.2f} | "
                     f"{'pass' if s['passes_step7'] else 'fail'} |")
        if d["ablation"]:
            L += ["", f"Each effect off in turn (axis {a}, seed 0):", "",
                  "| effect off | crossings (Hz) | chosen (Hz) | PW0 (%) | status |", "|---|---|---|---|---|"]
            for e, o in d["ablation"].items():
                L.append(f"| {e} | {', '.join(f'{x:.4g}' for x in o['crossings_hz']) or 'none'} | "
                         f"{_fmt(o['chosen_hz'])} | {_fmt(o['pw0_pct'], '.2f')} | {o['status']} |")
    return "\n".join(L) + "\n"


def _plot_effects(folder: Path, studies: dict[str, AxisStudy]) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    folder.mkdir(parents=True, exist_ok=True)
    for a, st in studies.items():
        fig, ax = plt.subplots(figsize=(7.5, 4.2), dpi=110)
        f, rel = _relative_curve(st.sessions[0])
        ax.semilogx(f, rel, "o-", color="k", ms=3, label="all effects (seed 0)")
        for k, r in enumerate(st.sessions[1:], 1):
            ax.semilogx(*_relative_curve(r), "-", color="0.75", lw=0.6, label="other seeds" if k == 1 else None)
        for i, (e, o) in enumerate(st.ablation.items()):
            ax.semilogx(f, o["curve_rel_pct"], "--", color=f"C{i}", lw=1, label=f"{e} off")
        ax.axhline(0.0, color="C3", lw=0.8)
        ax.set_xlabel("PWM frequency (Hz)")
        ax.set_ylabel("torque at 50 % - tau_max/2 (% of tau_max/2)")
        ax.set_title(f"axis {a}: where the 50 % torque crosses tau_max/2, and which effect puts it there")
        ax.grid(alpha=0.3, which="both")
        ax.legend(fontsize=7)
        fig.tight_layout()
        fig.savefig(folder / f"fig10_{a}_effects.png")
        plt.close(fig)
