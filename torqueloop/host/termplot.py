# SPDX-License-Identifier: MIT
"""A live plot in plain text, for a terminal without a display (``torqueloop
shell``): position against set-point, following error and PWM command of one
axis over the last telemetry records, as three strip charts.  A frame is a
string; the shell prints it and can append it to a file."""

from __future__ import annotations

from typing import Sequence

WIDTH, HEIGHT = 64, 8


def _scale(values: Sequence[float], height: int) -> tuple[float, float]:
    lo, hi = min(values), max(values)
    if hi - lo < 1e-9:
        lo, hi = lo - 1, hi + 1
    return lo, hi


def _row(v: float, lo: float, hi: float, height: int) -> int:
    """Row 0 is the top."""
    return height - 1 - min(height - 1, max(0, int(round((v - lo) / (hi - lo) * (height - 1)))))


def strip(series: dict[str, tuple[str, Sequence[float]]], width: int = WIDTH, height: int = HEIGHT,
          title: str = "") -> list[str]:
    """One chart: ``series`` maps a label to (mark, values), all on one scale;
    the last ``width`` values, newest on the right."""
    tails = {k: list(v)[-width:] for k, (_, v) in series.items()}
    allv = [x for v in tails.values() for x in v]
    if not allv:
        return [title, "(no data)"]
    lo, hi = _scale(allv, height)
    grid = [[" "] * width for _ in range(height)]
    for k, (mark, _) in series.items():
        vals = tails[k]
        off = width - len(vals)
        for i, v in enumerate(vals):
            grid[_row(v, lo, hi, height)][off + i] = mark
    lab = max(len(f"{hi:.6g}"), len(f"{lo:.6g}"))
    legend = "  ".join(f"{mark} {k} {tails[k][-1]:.6g}" for k, (mark, _) in series.items())
    out = [f"{title}: {legend}"]
    for r, cells in enumerate(grid):
        y = f"{hi:.6g}" if r == 0 else f"{lo:.6g}" if r == height - 1 else ""
        out.append(f"{y:>{lab}} |{''.join(cells)}|")
    return out


def frame(records: Sequence[dict], axis: int, unit: str, to_unit, n: int = 0, width: int = WIDTH,
          height: int = HEIGHT) -> str:
    """The frame for the newest ``width`` records: ``to_unit(counts)`` converts positions to ``unit``."""
    recs = list(records)[-width:]
    if not recs:
        return f"frame {n}: no telemetry yet"
    ax = [r["axes"][axis] for r in recs]
    t = recs[-1]["time_us"] / 1e6
    lines = [f"frame {n}  axis {axis}  t {t:.3f} s  ({len(recs)} records)"]
    lines += strip({"set-point": ("-", [to_unit(a["setpoint"]) for a in ax]),
                    "position": ("*", [to_unit(a["position"]) for a in ax])}, width, height,
                   f"position [{unit}]")
    lines += strip({"error": ("e", [a["error"] for a in ax])}, width, max(3, height // 2), "error [counts]")
    lines += strip({"command": ("c", [a["pwm_cmd"] for a in ax])}, width, max(3, height // 2), "PWM command")
    return "\n".join(lines)
