#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Pure-model P, PD and PID step responses (paper Figs 14-16, "simulation").

Runs torqueloop.sim.model_loop.run_loop for each law with the Table 1 gains: both
axes step to 6.28 rad (one screw turn, 4 mm) from rest, the controller
sampled every 25 ms, PWM at 450 Hz (x) / 200 Hz (z) through the BTS7960 model
into the plant's fast stepper.  Writes, per law, ``step_<law>.csv`` (every
sample) and ``step_<law>.png``, plus ``step_all.png`` and ``metrics.csv``,
into ``build/plant/`` (or --out), and prints rise time, overshoot, final
error and RMSE (eq 26) per axis.
"""

from __future__ import annotations

import argparse
import csv
import sys
import time
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

from torqueloop.sim.model_loop import TABLE1, LoopConfig, LoopResult, run_loop  # noqa: E402
from torqueloop.spec.metrics import step_metrics  # noqa: E402

REPO = Path(__file__).resolve().parent.parent
AXES = ("x", "z")


def write_csv(path: Path, r: LoopResult) -> None:
    with open(path, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["t_s"] + [f"{c}_{a}" for a in AXES for c in
                              ("x_meas_rad", "x_model_rad", "table_mm", "v_est_rad_s", "duty", "current_A")])
        for k in range(len(r.t)):
            row = [f"{r.t[k]:.4f}"]
            for a in range(2):
                row += [f"{r.x_meas[k, a]:.6f}", f"{r.x_true[k, a]:.6f}", f"{r.table_mm[k, a]:.6f}",
                        f"{r.v_est[k, a]:.5f}", f"{r.duty[k, a]:.5f}", f"{r.current[k, a]:.5f}"]
            w.writerow(row)


def plot(path: Path, law: str, r: LoopResult, setpoint: float) -> None:
    fig, axs = plt.subplots(3, 1, figsize=(8, 8), sharex=True)
    for a, name in enumerate(AXES):
        axs[0].plot(r.t, r.x_meas[:, a], label=f"axis {name} (encoder)")
        axs[1].plot(r.t, r.v_est[:, a], label=f"axis {name}")
        axs[2].plot(r.t, r.duty[:, a], label=f"axis {name}")
    axs[0].axhline(setpoint, color="k", lw=0.8, ls="--", label="x_d = 6.28 rad")
    axs[0].set_ylabel("screw angle (rad)")
    axs[1].set_ylabel("speed estimate (rad/s)")
    axs[2].set_ylabel("duty (signed)")
    axs[2].set_xlabel("time (s)")
    for ax in axs:
        ax.grid(True, alpha=0.3)
        ax.legend(loc="best", fontsize=8)
    axs[0].set_title(f"{law} control, pure model (Table 1 gains, Table 2 plant)")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", type=Path, default=REPO / "build" / "plant")
    ap.add_argument("--t-end", type=float, default=40.0, help="simulated time per law (s), paper T = 40")
    ap.add_argument("--laws", nargs="*", default=list(TABLE1))
    ap.add_argument("--drive", choices=("brake", "coast"), default="brake")
    ap.add_argument("--pw0", type=int, default=0, help="dead-zone compensation PW0 of eq. (1), ticks of 1023")
    ap.add_argument("--plant", default="paper", help="plant variant (paper-printed, paper, lab, lab-no-EFFECT) [paper]")
    args = ap.parse_args(argv)
    from sim_models.params import PlantParamError
    from sim_models.variants import plant_of

    try:
        params = plant_of(args.plant).params()
    except PlantParamError as e:
        print(f"plant_step: {e}", file=sys.stderr)
        return 2
    args.out.mkdir(parents=True, exist_ok=True)
    results: dict[str, LoopResult] = {}
    rows = []
    for law in args.laws:
        cfg = LoopConfig(t_end_s=args.t_end, gains=TABLE1[law], drive=args.drive, pw0=args.pw0)
        print(f"[plant_step] {law}: simulating {args.t_end:g} s ...", flush=True)
        t0 = time.monotonic()
        r = run_loop(cfg, params, progress=False)
        results[law] = r
        write_csv(args.out / f"step_{law}.csv", r)
        plot(args.out / f"step_{law}.png", law, r, cfg.setpoint_rad)
        for a, name in enumerate(AXES):
            m = step_metrics(r.t, r.x_meas[:, a], cfg.setpoint_rad)
            rows.append({"law": law, "axis": name, **m.as_dict()})
            print(f"  axis {name}: rise {m.rise_time_s} s, overshoot {m.overshoot_pct:.1f} %, "
                  f"steady-state error {m.steady_state_error:+.4f} rad, RMSE {m.rmse:.4f} rad")
        print(f"  wall {time.monotonic() - t0:.1f} s, {r.calls} plant calls", flush=True)
    fig, axs = plt.subplots(2, 1, figsize=(8, 6), sharex=True)
    for law, r in results.items():
        for a in range(2):
            axs[a].plot(r.t, r.x_meas[:, a], label=law)
    for a, name in enumerate(AXES):
        axs[a].axhline(6.28, color="k", lw=0.8, ls="--")
        axs[a].set_ylabel(f"axis {name} (rad)")
        axs[a].grid(True, alpha=0.3)
        axs[a].legend(fontsize=8)
    axs[1].set_xlabel("time (s)")
    axs[0].set_title("P / PD / PID step responses, pure model")
    fig.tight_layout()
    fig.savefig(args.out / "step_all.png", dpi=110)
    plt.close(fig)
    with open(args.out / "metrics.csv", "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)
    print(f"[plant_step] wrote {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
