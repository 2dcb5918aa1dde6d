# SPDX-License-Identifier: MIT
"""Figures like the paper's Fig. 10 (torque vs frequency, step 5) and
Fig. 11 (torque vs duty, steps 6-7), as PNG files."""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")  # files only; no display on a build machine
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from .method import Linearity, MotorResult  # noqa: E402


def plot_frequency(result: MotorResult, path: str | Path, title: str = "") -> Path:
    """Fig. 10: torque at 50 % duty vs frequency, the tau_max/2 line, the
    step-5 candidates and the chosen frequency."""
    fs, s5 = result.freq_sweep, result.step5
    fig, ax = plt.subplots(figsize=(7, 4.2), dpi=110)
    ax.plot(fs.x, fs.torque_nm, "o-", color="C0", label=f"torque at {fs.duty_pct:.4g} % duty")
    ax.axhline(s5.target_nm, color="C3", ls="--",
               label=f"target tau_max x {fs.duty_pct:.4g} % = {s5.target_nm:.4g} N m")
    for c in s5.candidates:
        ax.plot([c.freq_hz], [c.torque_nm], "x", color="0.4", ms=9)
    if result.chosen is not None:
        c = result.chosen
        ax.axvline(c.freq_hz, color="C2", ls=":")
        ax.plot([c.freq_hz], [c.torque_nm], "o", mfc="none", mec="C2", ms=13,
                label=f"chosen {c.freq_hz:.4g} Hz")
    ax2 = ax.twinx()
    ax2.plot(fs.x, fs.current_a, ".:", color="C1", alpha=0.7)
    ax2.set_ylabel("current (A)", color="C1")
    # From zero, as Fig. 10: a flat curve must look flat, not like a slope
    # magnified into the plot's height.
    ax.set_ylim(0, 1.15 * max(float(fs.torque_nm.max()), s5.target_nm))
    ax2.set_ylim(0, 1.15 * max(float(fs.current_a.max()), 1e-9))
    if fs.x.max() > 20 * fs.x.min():
        ax.set_xscale("log")   # a sweep over decades (the simulated bench: 50 Hz - 24 kHz)
    ax.set_xlabel("PWM frequency (Hz)")
    ax.set_ylabel("torque (N m)")
    ax.set_title(title or f"step 5: {fs.motor or fs.source}")
    ax.grid(alpha=0.3)
    ax.legend(loc="best", fontsize=8)
    return _save(fig, path)


def plot_duty(result: MotorResult, lin: Linearity, path: str | Path, title: str = "") -> Path:
    """Fig. 11: torque vs duty with the fitted dead-zone line and PW0."""
    att = next(a for a in result.attempts if a.linearity is lin)
    ds = att.duty_sweep
    assert ds is not None
    fig, ax = plt.subplots(figsize=(7, 4.2), dpi=110)
    ax.plot(ds.x, ds.torque_nm, "o", color="C0", ms=4, label="measured")
    if np.isfinite(lin.slope_nm_per_pct):
        d = np.linspace(0, 100, 401)
        ax.plot(d, lin.model_nm(d), "-", color="C3",
                label=f"fit: R^2 {lin.r2:.4f}, worst {lin.worst_dev_frac:.1%} of tau_max")
        ax.axvspan(0, lin.pw0_pct, color="0.85", label=f"dead zone PW0 = {lin.pw0_pct:.2f} %")
    ax.axhline(lin.tau_max_nm, color="0.5", ls="--", lw=0.8, label=f"tau_max = {lin.tau_max_nm:.3g} N m")
    ax2 = ax.twinx()
    ax2.plot(ds.x, ds.current_a, ".:", color="C1", alpha=0.7)
    ax2.set_ylabel("current (A)", color="C1")
    ax2.set_ylim(0, 1.15 * max(float(ds.current_a.max()), 1e-9))
    ax.set_xlabel("duty (%)")
    ax.set_ylabel("torque (N m)")
    verdict = "passes step 7" if lin.ok else "fails step 7"
    ax.set_title(title or f"steps 6-7 at {lin.freq_hz:.4g} Hz: {verdict}")
    ax.set_xlim(0, 100)
    ax.grid(alpha=0.3)
    ax.legend(loc="upper left", fontsize=8)
    return _save(fig, path)


def _save(fig: "plt.Figure", path: str | Path) -> Path:
    fig.tight_layout()
    p = Path(path)
    p.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(p)
    plt.close(fig)
    return p


def plot_result(result: MotorResult, out_dir: str | Path, stem: str) -> list[Path]:
    """Every figure for one motor: fig10 and one fig11 per duty sweep tried."""
    out = Path(out_dir)
    files = [plot_frequency(result, out / f"{stem}_fig10_torque_vs_freq.png")]
    for a in result.attempts:
        if a.linearity is not None:
            files.append(plot_duty(result, a.linearity, out / f"{stem}_fig11_torque_vs_duty_{a.candidate.freq_hz:.0f}hz.png"))
    return files
