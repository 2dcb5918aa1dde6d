# SPDX-License-Identifier: MIT
"""Telemetry records -> arrays, step-response figures, CSV and plots.

A record is what :func:`torqueloop.spec.protocol.decode_telemetry` returns:
``{"time_us": .., "axes": [{"setpoint", "position", "velocity_q8", "error",
"pwm_cmd", "faults", "enabled"}, ...]}``.

Step figures (for a step from ``start`` to ``target``, in counts):

- overshoot: the largest excursion past the target, % of the step;
- rise time: 10 % to 90 % of the step;
- settling time: from the step until the response last leaves the band
  ``target +- max(band_frac * |step|, band_min_counts)``; NaN if it never
  settles within the capture;
- steady-state error: target - mean of the last 10 % of the samples;
- RMSE of the position error, paper eq. (26): sqrt(1/T int e(t)^2 dt)
  (trapezoidal integral over the capture, e = set-point - position).
"""

from __future__ import annotations

import csv
from dataclasses import dataclass
from pathlib import Path
from typing import Sequence

import numpy as np

from torqueloop.spec.metrics import StepMetrics, step_metrics
from torqueloop.spec.units import Mechanics

FIELDS = ("setpoint", "position", "error", "velocity_q8", "pwm_cmd", "faults", "enabled")


@dataclass(frozen=True)
class Capture:
    t: np.ndarray                 # s, from the first record
    data: dict[str, np.ndarray]   # field -> (n, axes)

    @property
    def n(self) -> int:
        return len(self.t)


def to_capture(records: Sequence[dict]) -> Capture:
    if not records:
        raise ValueError("no telemetry records (is the board streaming? see `torqueloop monitor`)")
    us = np.array([r["time_us"] for r in records], dtype=np.int64)
    # time_us is a u32 on the wire: unwrap after 71.6 minutes
    us = np.concatenate([[0], np.cumsum(np.diff(us) % (1 << 32))]) + us[0]
    t = (us - us[0]) / 1e6
    data = {f: np.array([[ax[f] for ax in r["axes"]] for r in records], dtype=np.float64) for f in FIELDS}
    return Capture(t, data)


#: the position fields of a StepMetrics, converted by :func:`in_unit`
_POSITIONS = ("start", "target", "steady_state_error", "final_error", "rmse", "peak", "band")


def step_figures(t: np.ndarray, x: np.ndarray, sp: np.ndarray, start: float, target: float,
                 band_frac: float = 0.02, band_min_counts: float = 2.0) -> StepMetrics:
    """Figures of one axis's step (t from the step command, x and sp in
    counts), by the project's one definition (torqueloop.spec.metrics); the
    settling band is at least ``band_min_counts`` (the encoder's resolution)."""
    return step_metrics(t, x, target, start, sp, band_frac, band_min_counts)


def in_unit(m: StepMetrics, mech: Mechanics, unit: str) -> dict[str, float | str | None]:
    """The figures with every position both in counts (``<name>_counts``) and
    in ``unit`` (``<name>_<unit>``); times and percentages as they are."""
    d: dict[str, float | str | None] = {k: v for k, v in m.as_dict().items() if k not in _POSITIONS}
    for k in _POSITIONS:
        d[f"{k}_counts"] = float(getattr(m, k))
        if unit != "counts":
            d[f"{k}_{unit}"] = mech.from_counts(float(getattr(m, k)), unit)
    d["unit"] = unit
    return d


def fmt_s(v: float | None) -> str:
    return "not settled" if v is None else f"{v:.3f} s"


def write_csv(path: Path, cap: Capture, mech: Mechanics, unit: str = "rad") -> None:
    axes = cap.data["position"].shape[1]
    with open(path, "w", newline="") as f:
        w = csv.writer(f)
        head = ["t_s"]
        for a in range(axes):
            head += [f"setpoint_{a}_counts", f"position_{a}_counts", f"error_{a}_counts",
                     f"velocity_{a}_counts_s", f"pwm_cmd_{a}", f"faults_{a}", f"enabled_{a}",
                     f"setpoint_{a}_{unit}", f"position_{a}_{unit}"]
        w.writerow(head)
        for k in range(cap.n):
            row: list[str] = [f"{cap.t[k]:.6f}"]
            for a in range(axes):
                d = {fld: cap.data[fld][k, a] for fld in FIELDS}
                row += [str(int(d["setpoint"])), str(int(d["position"])), str(int(d["error"])),
                        f"{d['velocity_q8'] / 256:.3f}", str(int(d["pwm_cmd"])), str(int(d["faults"])),
                        str(int(d["enabled"])), f"{mech.from_counts(d['setpoint'], unit):.6f}",
                        f"{mech.from_counts(d['position'], unit):.6f}"]
            w.writerow(row)


def read_csv(path: Path) -> Capture:
    """Inverse of :func:`write_csv` (counts columns), for replotting a capture."""
    with open(path, newline="") as f:
        rows = list(csv.DictReader(f))
    axes = sum(1 for k in rows[0] if k.startswith("position_") and k.endswith("_counts"))
    t = np.array([float(r["t_s"]) for r in rows])
    col = {"setpoint": "setpoint_{}_counts", "position": "position_{}_counts", "error": "error_{}_counts",
           "pwm_cmd": "pwm_cmd_{}", "faults": "faults_{}", "enabled": "enabled_{}"}
    data = {k: np.array([[float(r[c.format(a)]) for a in range(axes)] for r in rows]) for k, c in col.items()}
    data["velocity_q8"] = np.array([[float(r[f"velocity_{a}_counts_s"]) * 256 for a in range(axes)]
                                    for r in rows])
    return Capture(t, data)


def plot(path: Path | None, cap: Capture, mech: Mechanics, unit: str = "rad",
         axes: Sequence[int] = (0, 1), title: str = "", figures: Sequence[tuple[int, StepMetrics]] = ()):
    """Position and set-point, error, velocity and PWM command against time.
    Saved to ``path`` (PNG) if given; returns the figure."""
    import matplotlib
    if path is not None:
        matplotlib.use("Agg", force=False)
    import matplotlib.pyplot as plt

    fig, axs = plt.subplots(4, 1, figsize=(9, 9), sharex=True)
    for a in axes:
        pos = [mech.from_counts(v, unit) for v in cap.data["position"][:, a]]
        sp = [mech.from_counts(v, unit) for v in cap.data["setpoint"][:, a]]
        axs[0].plot(cap.t, pos, label=f"axis {a} position")
        axs[0].plot(cap.t, sp, "--", drawstyle="steps-post", label=f"axis {a} set-point")
        axs[1].plot(cap.t, [mech.from_counts(v, unit) for v in cap.data["error"][:, a]], label=f"axis {a}")
        axs[2].plot(cap.t, [mech.from_counts(v / 256, unit) for v in cap.data["velocity_q8"][:, a]],
                    label=f"axis {a}")
        axs[3].step(cap.t, cap.data["pwm_cmd"][:, a], where="post", label=f"axis {a}")
    axs[0].set_ylabel(f"position ({unit})")
    axs[1].set_ylabel(f"error ({unit})")
    axs[2].set_ylabel(f"velocity ({unit}/s)")
    axs[3].set_ylabel("PWM command (of 1023)")
    axs[3].set_xlabel("time (s)")
    for ax in axs:
        ax.grid(True, alpha=0.3)
        ax.legend(loc="best", fontsize=8)
    text = []
    for axis, f in figures:
        text.append(f"axis {axis}: overshoot {f.overshoot_pct:.1f} %, rise {fmt_s(f.rise_time_s)}, "
                    f"settling {fmt_s(f.settling_time_s)}, RMSE {mech.from_counts(f.rmse, unit):.4g} {unit}")
    fig.suptitle("\n".join([title] + text) if title or text else "", fontsize=9)
    fig.tight_layout()
    if path is not None:
        fig.savefig(path, dpi=110)
    return fig
