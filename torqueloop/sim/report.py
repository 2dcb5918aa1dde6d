# SPDX-License-Identifier: MIT
"""The experiment's report (build/report/): the paper's comparison of a
model arm with an experiment arm (Table 3, Figs 14-16), what the method buys
(PW0 and the chosen carrier against rejected ones), the implementation check,
and the title question - what the PWM frequency does to the closed loop.

Every metric is torqueloop.spec.metrics (the one definition); copper loss
and current ripple come from the plant's exact current integrals.

``report.json`` keys (stable; docs/experiment.md lists them):

* ``table3.<law>.rmse_position_rad``, ``.rmse_velocity_rad_s`` - eq. (27),
  model arm against experiment arm; ``.per_axis.<x|z>.rmse_position_rad`` and
  ``.rmse_velocity_rad_s`` - eq. (26);
* ``arms.<model|experiment>.<law>.<x|z>`` - the step metrics of each arm;
* ``implementation_check.<law>.rmse_position_rad``, ``.rmse_velocity_rad_s``
  (and ``.per_axis``, ``.carrier_start_clk``) - RTL arm against the fast path on
  the same plant, settings and carrier phase;
* ``cases.<name>.<law>`` - the experiment arm's cases on the fast path, with
  their RMSE against the model arm and their step metrics;
* ``sweep`` - rows ``{freq_hz, pw0, law, axis, ...metrics}``;
* ``characterization``, ``interpretations``, ``meta``.
"""

from __future__ import annotations

import json
import math
import shutil
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from torqueloop.sim.experiment import COUNTS_PER_REV, ModelRun, RtlRun, Trajectory
from torqueloop.spec.metrics import rmse, step_metrics

AXES = ("x", "z")
RAD_PER_COUNT = 2 * math.pi / COUNTS_PER_REV

#: what this project reads into the paper where it is silent or contradicts itself (docs/*.md argue each)
INTERPRETATIONS = [
    "Model arm = the paper's simulation: eq. (7) and (17) on the `paper` plant, the armature voltage averaged "
    "over the PWM period (an ideal source held per 25 ms sample), position without encoder quantisation "
    "(motor angle / G), u = tau / tau_max (paper's 2.4 / 2.08 N m) saturated at +-1 (docs/experiment.md).",
    "Both arms run the firmware's law: filtered Euler speed v_k = 0.5 (x_k - x_k-1)/T_s + 0.5 v_k-1 (sec. VI.B) "
    "and the integral held while saturated towards the error; the paper's own firmware law is not published.",
    "Table 1 'Given value' = output-shaft torque per rad of screw angle (per rad/s, per rad s) "
    "(docs/plant.md, 'Table 1').",
    "`paper` plant = Table 2 with I_m2 = 9.655e-6 kg m^2 (printed 9.655e-5; docs/plant.md, 'The paper variant').",
    "Experiment arm plant = `lab`: `paper` + motor-side stiction, brush drop, asymmetric gear efficiency, "
    "k_t = k_e (docs/plant.md, 'The lab variant'); the model arm does not know these.",
    "The experiment arm is configured from the characterisation file through the host tool's `config load` "
    "(FDIV, PW0, PW_F and the measured tau_max), then the Table 1 gains in physical units.",
    "RMSE (eq. 26-27): samples j of both arms at the control instants from the step, trapezoid integral over T; "
    "i = position (rad) and velocity (the controller's estimate, rad/s).",
    "The PWM period is 1023 ticks of Count_max clocks (eq. 2-4 with gamma = 2^10 - 1): docs/freq_div.md.",
]


def axis_metrics(tr: Trajectory, target_rad: float, a: int, resistance_ohm: float | None = None) -> dict[str, Any]:
    """One axis of one run: the step metrics (spec.metrics), the tracking
    RMSE of eq. (26) against the set-point, and from the current integrals
    the copper loss (R x integral of i^2 over T) and the current ripple
    (RMS of i about its mean over the last quarter of the run)."""
    m = step_metrics(tr.t, tr.pos[:, a], target_rad)
    out: dict[str, Any] = {
        "overshoot_pct": m.overshoot_pct,
        "settling_time_s": m.settling_time_s,
        "rise_time_s": m.rise_time_s,
        "steady_state_error_rad": m.steady_state_error,
        "steady_state_error_counts": m.steady_state_error / RAD_PER_COUNT,
        "tracking_rmse_rad": m.rmse,
    }
    if tr.true_pos is not None:     # at the screw, beyond the gearbox's backlash the encoder cannot see
        out["screw_steady_state_error_counts"] = (step_metrics(tr.t, tr.true_pos[:, a], target_rad).steady_state_error
                                                  / RAD_PER_COUNT)
    if tr.i2 is not None and tr.charge is not None and resistance_ohm is not None:
        out["copper_loss_J"] = resistance_ohm * float(tr.i2[-1, a] - tr.i2[0, a])
        k = int(len(tr.t) * 0.75)
        dt = float(tr.t[-1] - tr.t[k])
        if dt > 0:
            mean = (tr.charge[-1, a] - tr.charge[k, a]) / dt
            msq = (tr.i2[-1, a] - tr.i2[k, a]) / dt
            out["current_ripple_A_rms"] = math.sqrt(max(0.0, msq - mean * mean))
            out["current_mean_A"] = mean
    return out


def run_metrics(run: RtlRun | ModelRun, target_rad: float) -> dict[str, dict[str, Any]]:
    r = getattr(run, "resistance_ohm", ()) or (None, None)
    return {ax: axis_metrics(run.traj, target_rad, i, r[i]) for i, ax in enumerate(AXES)}


def compare(a: Trajectory, b: Trajectory) -> dict[str, Any]:
    """Eq. (26) per axis and eq. (27) over both, position and velocity, sample for sample."""
    n = min(len(a.t), len(b.t))
    t = a.t[:n]
    out: dict[str, Any] = {
        "rmse_position_rad": rmse(t, a.pos[:n] - b.pos[:n]),
        "rmse_velocity_rad_s": rmse(t, a.vel[:n] - b.vel[:n]),
        "per_axis": {},
    }
    for i, ax in enumerate(AXES):
        d = a.pos[:n, i] - b.pos[:n, i]
        out["per_axis"][ax] = {"rmse_position_rad": rmse(t, d),
                               "rmse_velocity_rad_s": rmse(t, a.vel[:n, i] - b.vel[:n, i]),
                               "max_abs_diff_counts": int(round(float(np.abs(d).max()) / RAD_PER_COUNT))}
    return out


@dataclass
class Study:
    """Everything make run collects (torqueloop.study.experiment)."""

    t_end_s: float
    target_rad: float
    laws: list[str]
    model_arm: dict[str, ModelRun] = field(default_factory=dict)
    experiment_arm: dict[str, RtlRun] = field(default_factory=dict)
    fast_check: dict[str, ModelRun] = field(default_factory=dict)
    cases: dict[str, dict[str, ModelRun]] = field(default_factory=dict)
    case_labels: dict[str, str] = field(default_factory=dict)
    sweep: list[tuple[float, bool, str, ModelRun]] = field(default_factory=list)
    sweep_t_end_s: float | None = None
    characterization: dict[str, Any] = field(default_factory=dict)
    meta: dict[str, Any] = field(default_factory=dict)


def build(st: Study) -> dict[str, Any]:
    rep: dict[str, Any] = {"schema": "torqueloop-experiment-report", "schema_version": 2,
                           "meta": st.meta | {"T_s": st.t_end_s, "step_rad": st.target_rad},
                           "characterization": st.characterization,
                           "interpretations": INTERPRETATIONS,
                           "table3": {}, "arms": {"model": {}, "experiment": {}},
                           "implementation_check": {}, "cases": {}, "sweep": []}
    for law in st.laws:
        m, e = st.model_arm.get(law), st.experiment_arm.get(law)
        if m is not None:
            rep["arms"]["model"][law] = run_metrics(m, st.target_rad)
        if e is not None:
            rep["arms"]["experiment"][law] = run_metrics(e, st.target_rad) | {"run": _rtl_run(e)}
        if m is not None and e is not None:
            rep["table3"][law] = compare(m.traj, e.traj)
        f = st.fast_check.get(law)
        if f is not None and e is not None:
            rep["implementation_check"][law] = compare(e.traj, f.traj) | {
                "fast_path": run_metrics(f, st.target_rad), "fast_path_wall_s": f.wall_s,
                "carrier_start_clk": list(e.carrier_start_clk)}
    for name, runs in st.cases.items():
        rep["cases"][name] = {"description": st.case_labels.get(name, name)}
        for law, r in runs.items():
            row: dict[str, Any] = {"metrics": run_metrics(r, st.target_rad), "config": r.config}
            if law in st.model_arm:
                row["against_model_arm"] = compare(st.model_arm[law].traj, r.traj)
            rep["cases"][name][law] = row
    for f, pw0, law, r, *extra in st.sweep:      # extra: per-axis keys of the point ({x: {...}, z: {...}})
        ex = extra[0] if extra else {}
        for ax, mm in run_metrics(r, ex.get("target_rad", st.target_rad)).items():
            rep["sweep"].append({"freq_hz": f, "pw0": pw0, "law": law, "axis": ax, **ex.get(ax, {}), **mm})
    rep["meta"]["sweep_T_s"] = st.sweep_t_end_s
    return rep


def _rtl_run(e: RtlRun) -> dict[str, Any]:
    return {"cycles": e.cycles, "wall_s": e.wall_s, "cpu_s": e.cpu_s,
            "cycles_per_cpu_s": e.cycles / e.cpu_s if e.cpu_s else None,
            "board_settings": list(e.board), "fault_flags_seen": e.faults,
            "faults_after_configuration": e.config_faults, "link_errors": e.link_errors,
            "uart_framing_errors": e.uart_errors, "bridge": e.bridge}


def write(st: Study, out: Path) -> dict[str, Any]:
    """report.json, report.md and the PNGs in ``out``."""
    out.mkdir(parents=True, exist_ok=True)
    rep = build(st)
    for law in st.laws:
        if law in st.model_arm or law in st.experiment_arm:
            _plot_step(law, st, out / f"fig14_16_step_{law}.png")
    if st.sweep:
        _plot_sweep(rep, out / "pwm_frequency_sweep.png")
    for src in st.characterization.get("plots", []):
        p = Path(src)
        if p.exists():
            shutil.copy(p, out / p.name)
    (out / "report.json").write_text(json.dumps(rep, indent=2, default=_json))
    (out / "report.md").write_text(markdown(rep))
    return rep


def _json(o: Any) -> Any:
    if isinstance(o, (np.floating, np.integer)):
        return o.item()
    if isinstance(o, np.ndarray):
        return o.tolist()
    if isinstance(o, Path):
        return str(o)
    raise TypeError(type(o))


def _f(v: Any, spec: str = ".3f") -> str:
    return "-" if v is None else format(v, spec)


def markdown(rep: dict[str, Any]) -> str:
    m = rep["meta"]
    L = ["# The paper's experiment: model arm against experiment arm", "",
         f"Step of {m['step_rad']:.4g} rad on both axes, T = {m['T_s']:g} s "
         f"(sec. VI.B); wall time {_f(m.get('wall_s_total'), '.0f')} s.", ""]
    ch = rep["characterization"]
    if ch:
        L += ["## The characterisation the experiment arm is configured from", "",
              f"`{ch.get('config')}` ({ch.get('source', '')}):", "",
              "| axis | chosen PWM (Hz) | on the board (Hz) | PW0 (counts) | tau_max measured (N m) |", "|---|---|---|---|---|"]
        for ax, a in ch.get("axes", {}).items():
            L.append(f"| {ax} | {a['pwm_freq_hz']:.4g} | {a['achieved_hz']:.4g} | {a['pw0_counts']} | {a['tau_max_nm']:.4g} |")
        L.append("")
    if rep["table3"]:
        L += ["## Table 3 analogue: RMSE between the model arm and the experiment arm (eq. 26-27)", "",
              "| law | position (rad), eq. 27 | x | z | velocity (rad/s), eq. 27 | x | z |", "|---|---|---|---|---|---|---|"]
        for law, v in rep["table3"].items():
            pa = v["per_axis"]
            L.append(f"| {law} | {v['rmse_position_rad']:.4f} | {pa['x']['rmse_position_rad']:.4f} | "
                     f"{pa['z']['rmse_position_rad']:.4f} | {v['rmse_velocity_rad_s']:.4f} | "
                     f"{pa['x']['rmse_velocity_rad_s']:.4f} | {pa['z']['rmse_velocity_rad_s']:.4f} |")
        L.append("")
    L += _arm_table(rep)
    if rep["implementation_check"]:
        L += ["## Implementation check: RTL in the loop against the fast path (same plant, same settings)", "",
              "This compares the board image and its pins with the firmware's law in Python on the same plant: it "
              "checks the implementation, and licenses the fast path for the cases and the sweep. It cannot "
              "see an error of interpretation: both sides share every assumption. The fast path's carriers "
              "start where the RTL run's first drove the bridge after the step (the carrier's phase is set "
              "by when the divider was written, not by the law).", "",
              "| law | position RMSE (rad) | velocity RMSE (rad/s) | max diff x / z (counts) | carrier start x / z "
              "(clocks after the step's sample) |", "|---|---|---|---|---|"]
        for law, v in rep["implementation_check"].items():
            pa = v["per_axis"]
            L.append(f"| {law} | {v['rmse_position_rad']:.5f} | {v['rmse_velocity_rad_s']:.4f} | "
                     f"{pa['x']['max_abs_diff_counts']} / {pa['z']['max_abs_diff_counts']} | "
                     f"{' / '.join(str(c) for c in v['carrier_start_clk'])} |")
        L.append("")
    if rep["cases"]:
        L += ["## What the method buys: the experiment arm's cases (fast path)", "",
              "| case | law | RMSE vs model arm (rad) | x: steady-state error (counts) | overshoot (%) | settling (s) |"
              " z: steady-state error (counts) | overshoot (%) | settling (s) | copper loss x / z (J) |",
              "|---|---|---|---|---|---|---|---|---|---|"]
        for name, v in rep["cases"].items():
            for law, row in v.items():
                if law == "description":
                    continue
                mx, mz = row["metrics"]["x"], row["metrics"]["z"]
                rm = row.get("against_model_arm", {}).get("rmse_position_rad")
                L.append(f"| {v['description']} | {law} | {_f(rm, '.4f')} | {mx['steady_state_error_counts']:.1f} | "
                         f"{mx['overshoot_pct']:.1f} | {_f(mx['settling_time_s'], '.2f')} | "
                         f"{mz['steady_state_error_counts']:.1f} | {mz['overshoot_pct']:.1f} | "
                         f"{_f(mz['settling_time_s'], '.2f')} | {_f(mx.get('copper_loss_J'), '.2f')} / "
                         f"{_f(mz.get('copper_loss_J'), '.2f')} |")
        L.append("")
    if rep["sweep"]:
        L += [f"## The title question: the PWM carrier and the closed loop (fast path, lab plant, T = "
              f"{_f(m.get('sweep_T_s'), 'g')} s)", "",
              "| f (Hz) | PW0 | law | axis | steady-state error (counts) | overshoot (%) | settling (s) | "
              "tracking RMSE (rad) | copper loss (J) | current ripple (A rms) |", "|---|---|---|---|---|---|---|---|---|---|"]
        for r in rep["sweep"]:
            L.append(f"| {r['freq_hz']:.4g} | {'on' if r['pw0'] else 'off'} | {r['law']} | {r['axis']} | "
                     f"{r['steady_state_error_counts']:.1f} | {r['overshoot_pct']:.1f} | {_f(r['settling_time_s'], '.2f')} | "
                     f"{r['tracking_rmse_rad']:.4f} | {_f(r.get('copper_loss_J'), '.2f')} | "
                     f"{_f(r.get('current_ripple_A_rms'), '.3f')} |")
        L += ["", "Figure: `pwm_frequency_sweep.png`.", ""]
    L += ["## Interpretations", ""] + [f"- {s}" for s in rep["interpretations"]] + [""]
    return "\n".join(L)


def _arm_table(rep: dict[str, Any]) -> list[str]:
    L = ["## Each arm's step response (settling: last entry into the 2 % band; steady-state error: mean of the last "
         "10 %)", "", "| law | axis | arm | overshoot (%) | settling (s) | steady-state error (counts) | "
         "tracking RMSE (rad) | copper loss (J) |", "|---|---|---|---|---|---|---|---|"]
    for law in [k for k in ("P", "PD", "PID") if k in rep["arms"]["experiment"] or k in rep["arms"]["model"]]:
        for ax in AXES:
            for arm in ("model", "experiment"):
                v = rep["arms"][arm].get(law, {}).get(ax)
                if v is None:
                    continue
                L.append(f"| {law} | {ax} | {arm} | {v['overshoot_pct']:.1f} | {_f(v['settling_time_s'], '.2f')} | "
                         f"{v['steady_state_error_counts']:.1f} | {v['tracking_rmse_rad']:.4f} | "
                         f"{_f(v.get('copper_loss_J'), '.2f')} |")
    return L + [""]


def save_figure(fig, axs, xlabel: str, path: Path) -> None:
    """A report figure's last touches: the bottom row's x label, the layout, the PNG."""
    import matplotlib.pyplot as plt

    for p in axs[-1]:
        p.set_xlabel(xlabel)
    fig.tight_layout()
    fig.savefig(path, dpi=90)
    plt.close(fig)


def _plot_step(law: str, st: Study, path: Path) -> None:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    m, e, f = st.model_arm.get(law), st.experiment_arm.get(law), st.fast_check.get(law)
    fig, axs = plt.subplots(3, 2, figsize=(12, 9.5), sharex=True)
    for i, ax in enumerate(AXES):
        for row, (key, unit) in enumerate((("pos", "position (rad)"), ("vel", "velocity (rad/s)"), ("cmd", "PWM command"))):
            p = axs[row, i]
            if m is not None:
                p.plot(m.traj.t, getattr(m.traj, key)[:, i], "C1-", lw=1.6, label="model arm (paper's simulation)")
            if e is not None:
                p.plot(e.traj.t, getattr(e.traj, key)[:, i], "C0--", lw=1.2, label="experiment arm (RTL, lab plant)")
            if f is not None:
                p.plot(f.traj.t, getattr(f.traj, key)[:, i], "C3:", lw=0.9, label="fast path (same settings)")
            p.set_ylabel(unit)
            if row == 0:
                p.axhline(st.target_rad, color="0.6", lw=0.6)
                p.set_title(f"{law}: axis {ax}")
                p.legend(fontsize=8)
    save_figure(fig, axs, "time (s)", path)


def _plot_sweep(rep: dict[str, Any], path: Path) -> None:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    rows = rep["sweep"]
    laws = sorted({r["law"] for r in rows}, key=["P", "PD", "PID"].index)
    keys = (("steady_state_error_counts", "steady-state error (counts)", True),
            ("overshoot_pct", "overshoot (%)", False), ("tracking_rmse_rad", "tracking RMSE (rad)", False),
            ("copper_loss_J", "copper loss (J)", False), ("current_ripple_A_rms", "current ripple (A rms)", False))
    fig, axs = plt.subplots(len(keys), 2, figsize=(12, 14), sharex=True)
    for i, ax in enumerate(AXES):
        for row, (k, label, absval) in enumerate(keys):
            p = axs[row, i]
            for j, law in enumerate(laws):
                for pw0, ls in ((True, "-"), (False, ":")):
                    pts = sorted((r["freq_hz"], r.get(k)) for r in rows
                                 if r["law"] == law and r["axis"] == ax and r["pw0"] == pw0 and r.get(k) is not None)
                    if pts:
                        x, y = zip(*pts)
                        p.semilogx(x, np.abs(y) if absval else y, ls, marker="o", ms=3, color=f"C{j}",
                                   label=f"{law}, PW0 {'on' if pw0 else 'off'}")
            p.set_ylabel(label)
            p.grid(alpha=0.3, which="both")
            if row == 0:
                p.set_title(f"axis {ax}: closed loop against the PWM carrier (lab plant)")
                p.legend(fontsize=7, ncol=2)
    save_figure(fig, axs, "PWM carrier (Hz)", path)
