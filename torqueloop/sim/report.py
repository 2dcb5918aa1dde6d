# SPDX-License-Identifier: MIT
"""Report of the step experiment: RTL in the loop against the pure model,
the analogue of the paper's Figs 14-16 and Table 3 (build/report/).

Metrics (torqueloop.spec.metrics, the one definition):
  - RMSE of eq. (26)-(27) between RTL and model, position and velocity, also per axis;
  - per run and axis: settling time, overshoot, steady-state error.
"""

from __future__ import annotations

import json
import math
from dataclasses import asdict
from pathlib import Path

import numpy as np

from torqueloop.sim.experiment import COUNTS_PER_REV, ModelRun, RtlRun, Trajectory
from torqueloop.spec.metrics import rmse, step_metrics

AXES = ("x", "z")


def _metrics(t: np.ndarray, x: np.ndarray, target: float) -> dict:
    """torqueloop.spec.metrics (the one definition) in rad, plus the
    steady-state error in encoder counts."""
    m = step_metrics(t, x, target).as_dict()
    m["steady_state_error_counts"] = m["steady_state_error"] * COUNTS_PER_REV / (2 * math.pi)
    return m


def compare(rtl: RtlRun, model: ModelRun, fw_model: ModelRun | None = None) -> dict:
    a, b = rtl.traj, model.traj
    n = min(len(a.t), len(b.t))
    t = a.t[:n]
    target = rtl.config.target_counts * 2 * math.pi / COUNTS_PER_REV
    out: dict = {
        "rmse_rad": rmse(t, a.pos[:n] - b.pos[:n]),
        "rmse_rad_s": rmse(t, a.vel[:n] - b.vel[:n]),
        "rmse_true_rad": rmse(t, a.true_pos[:n] - b.true_pos[:n]),
        "rmse_pct_of_step": 100 * rmse(t, a.pos[:n] - b.pos[:n]) / target,
        "per_axis": {},
    }
    if fw_model is not None:
        c = fw_model.traj
        m = min(n, len(c.t))
        out["rmse_rad_fw_law"] = rmse(t[:m], a.pos[:m] - c.pos[:m])
        out["rmse_rad_s_fw_law"] = rmse(t[:m], a.vel[:m] - c.vel[:m])
        out["rmse_rad_model_vs_fw_law"] = rmse(t[:m], b.pos[:m] - c.pos[:m])
    for i, ax in enumerate(AXES):
        d = a.pos[:n, i] - b.pos[:n, i]
        out["per_axis"][ax] = {
            "rmse_rad": rmse(t, d),
            "rmse_rad_s": rmse(t, a.vel[:n, i] - b.vel[:n, i]),
            "max_abs_diff_counts": int(round(np.abs(d).max() * COUNTS_PER_REV / (2 * math.pi))),
            "rtl": _metrics(t, a.pos[:n, i], target),
            "model": _metrics(t, b.pos[:n, i], target),
        }
    return out


def _plot(law: str, rtl: RtlRun, model: ModelRun, fw: ModelRun | None, path: Path) -> None:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    a, b = rtl.traj, model.traj
    fig, axs = plt.subplots(4, 2, figsize=(12, 12), sharex=True)
    for i, ax in enumerate(AXES):
        p = axs[0, i]
        p.plot(b.t, b.pos[:, i], "C1-", lw=1.5, label="pure model (encoder)")
        p.plot(a.t, a.pos[:, i], "C0--", lw=1.2, label="RTL in the loop (telemetry)")
        p.plot(rtl.trace_t, rtl.trace_pos[:, i], "C2:", lw=0.8, label="RTL plant, screw angle")
        if fw is not None:
            p.plot(fw.traj.t, fw.traj.pos[:, i], "C3-", lw=0.6, label="model, firmware's law")
        p.set_ylabel("position (rad)")
        p.set_title(f"{law}: axis {ax}")
        p.legend(fontsize=8)
        p = axs[1, i]
        p.plot(b.t, b.vel[:, i], "C1-", lw=1.5, label="pure model")
        p.plot(a.t, a.vel[:, i], "C0--", lw=1.2, label="RTL (firmware estimate)")
        p.plot(rtl.trace_t, rtl.trace_vel[:, i], "C2:", lw=0.6, label="RTL plant, screw speed")
        p.set_ylabel("velocity (rad/s)")
        p.legend(fontsize=8)
        p = axs[2, i]
        p.step(b.t, b.cmd[:, i], "C1-", where="post", lw=1.5, label="pure model")
        p.step(a.t, a.cmd[:, i], "C0--", where="post", lw=1.2, label="RTL")
        if fw is not None:
            p.step(fw.traj.t, fw.traj.cmd[:, i], "C3-", where="post", lw=0.6, label="model, firmware's law")
        p.set_ylabel("PWM command (of 1023)")
        p.legend(fontsize=8)
        p = axs[3, i]
        p.plot(b.t, b.err[:, i], "C1-", lw=1.5, label="pure model")
        p.plot(a.t, a.err[:, i], "C0--", lw=1.2, label="RTL")
        p.set_ylabel("tracking error (rad)")
        p.set_xlabel("time (s)")
        p.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=90)
    plt.close(fig)


def _traj_json(tr: Trajectory) -> dict:
    return {k: np.asarray(v).tolist() for k, v in asdict(tr).items()}


def write(results: dict[str, tuple], out: Path, meta: dict | None = None) -> dict:
    """Plots, report.json (every number, trajectories in data/) and report.md."""
    out.mkdir(parents=True, exist_ok=True)
    (out / "data").mkdir(exist_ok=True)
    rep: dict = {"meta": meta or {}, "laws": {}}
    for law, runs in results.items():
        rtl, model = runs[0], runs[1]
        fw = runs[2] if len(runs) > 2 else None
        cmp = compare(rtl, model, fw)
        _plot(law, rtl, model, fw, out / f"step_{law}.png")
        (out / "data" / f"{law}.json").write_text(json.dumps(
            {"rtl": _traj_json(rtl.traj), "model": _traj_json(model.traj)}))
        c = rtl.config
        rep["laws"][law] = cmp | {
            "config": {"t_end_s": c.t_end_s, "step_rad": c.step_rad, "target_counts": c.target_counts,
                       "period_us": c.period_us, "pwm_hz": list(c.pwm_hz), "pwm_hz_actual": list(c.pwm_hz_actual),
                       "fdiv": list(c.fdiv), "brake": c.brake},
            "rtl_run": {"cycles": rtl.cycles, "wall_s": rtl.wall_s, "cpu_s": rtl.cpu_s,
                        "cycles_per_wall_s": rtl.cycles / rtl.wall_s if rtl.wall_s else None,
                        "cycles_per_cpu_s": rtl.cycles / rtl.cpu_s if rtl.cpu_s else None,
                        "sample_to_plant_clock_jitter_s": rtl.t0_jitter_s, "bridge": rtl.bridge,
                        "fault_flags_seen": rtl.faults,
                        "faults_after_configuration": rtl.config_faults, "link_errors": rtl.link_errors,
                        "uart_framing_errors": rtl.uart_errors, "identify": rtl.identify},
            "model_run": {"wall_s": model.wall_s},
        }
    rep["rmse_rad"] = {law: v["rmse_rad"] for law, v in rep["laws"].items()}
    (out / "report.json").write_text(json.dumps(rep, indent=2, default=float))
    (out / "report.md").write_text(markdown(rep))
    return rep


def _fmt(v: object, spec: str = ".3f") -> str:
    return "-" if v is None else format(v, spec)


def markdown(rep: dict) -> str:
    lines = ["# RTL in the loop: the paper's step experiment (sec. VI.B)", ""]
    m = rep.get("meta", {})
    if m:
        lines += [f"- {k}: {v}" for k, v in m.items()] + [""]
    lines += ["## RMSE between RTL in the loop and the pure model (eq. 26-27, Table 3 analogue)", "",
              "| law | position RMSE (rad) | % of step | velocity RMSE (rad/s) | plant screw-angle RMSE (rad) |"
              " max diff x / z (counts) |",
              "|---|---|---|---|---|---|"]
    for law, v in rep["laws"].items():
        pa = v["per_axis"]
        lines.append(f"| {law} | {v['rmse_rad']:.4f} | {v['rmse_pct_of_step']:.2f} % | {v['rmse_rad_s']:.4f} | "
                     f"{v['rmse_true_rad']:.4f} | {pa['x']['max_abs_diff_counts']} / {pa['z']['max_abs_diff_counts']} |")
    if any("rmse_rad_fw_law" in v for v in rep["laws"].values()):
        lines += ["", "Against the second pure model (same plant, the firmware's law from torqueloop/models/servo.py, "
                  "the hardware's PWM):", "",
                  "| law | RTL vs firmware-law model: position RMSE (rad) | % of step | velocity RMSE (rad/s) |"
                  " torqueloop.sim.model_loop vs firmware-law model (rad) |", "|---|---|---|---|---|"]
        for law, v in rep["laws"].items():
            step = v["config"]["step_rad"]
            lines.append(f"| {law} | {v['rmse_rad_fw_law']:.4f} | {100 * v['rmse_rad_fw_law'] / step:.2f} % | "
                         f"{v['rmse_rad_s_fw_law']:.4f} | {v['rmse_rad_model_vs_fw_law']:.4f} |")
    lines += ["", "## Step response (settling: last entry into the 2 % band; steady-state error: mean of the "
              "last 10 % of the record)", "",
              "| law | axis | run | settling (s) | overshoot (%) | steady-state error (counts) |",
              "|---|---|---|---|---|---|"]
    for law, v in rep["laws"].items():
        for ax, pa in v["per_axis"].items():
            for who in ("rtl", "model"):
                s = pa[who]
                lines.append(f"| {law} | {ax} | {who} | {_fmt(s['settling_time_s'], '.2f')} | "
                             f"{s['overshoot_pct']:.1f} | {s['steady_state_error_counts']:.1f} |")
    lines += ["", "## Runs", "", "| law | simulated clocks | wall (s) | CPU (s) | Mclock/wall-s | Mclock/CPU-s |"
              " rollbacks / segments | faults |", "|---|---|---|---|---|---|---|---|"]
    for law, v in rep["laws"].items():
        r = v["rtl_run"]
        lines.append(f"| {law} | {r['cycles']:,} | {r['wall_s']:.1f} | {r['cpu_s']:.1f} | "
                     f"{r['cycles_per_wall_s'] / 1e6:.2f} | {r['cycles_per_cpu_s'] / 1e6:.2f} | "
                     f"{r['bridge']['rollbacks']} / {r['bridge']['segments']} | {r['fault_flags_seen']} |")
    lines += ["", "Plots: " + ", ".join(f"`step_{law}.png`" for law in rep["laws"]) +
              " (position, velocity, PWM command, tracking error; both axes).", ""]
    return "\n".join(lines)
