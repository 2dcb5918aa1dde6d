# SPDX-License-Identifier: MIT
"""Step-response metrics and the RMSE of eq. (26)-(27), defined once.

``torqueloop step-test`` (the host tool), the experiment report (make run)
and the pure-model studies all call :func:`step_metrics` and :func:`rmse`,
so the same trajectory gives the same numbers everywhere.

Definitions (a step from ``start`` to ``target``, samples x(t), t from the
step command):

* overshoot: the largest excursion beyond ``target`` in the step's
  direction, in % of the step (0 when it never passes the target);
* rise time: 10 % to 90 % of the step, crossings interpolated linearly
  between samples (None when 90 % is never reached);
* settling time: the instant of the sample after the last one outside the
  band |x - target| <= max(band_frac |step|, band_min) (2 % by default);
  0 when no sample is outside, None ("not settled") when the last sample is;
* steady-state error: target minus the mean of the last 10 % of the samples
  (at least one), so a limit cycle counts by its mean, not its phase; and
  the final error, target minus the last sample;
* tracking RMSE: eq. (26) of the error to the set-point over the record.

RMSE, eq. (26)-(27): sqrt(1/T integral_0^T sum_axes e_i(t)^2 dt), the
integral by the trapezoid rule over the samples; with one axis it is eq. (26).
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np

SETTLE_BAND = 0.02    # 2 % of the step
TAIL_FRACTION = 0.1   # steady state: the last 10 % of the record


def rmse(t: np.ndarray, e: np.ndarray) -> float:
    """Eq. (26) for ``e`` of shape (n,), eq. (27) for (n, axes): axes summed in square."""
    t = np.asarray(t, float)
    e = np.asarray(e, float)
    e2 = e**2 if e.ndim == 1 else (e**2).sum(axis=1)
    span = float(t[-1] - t[0]) if len(t) else 0.0
    if span <= 0:
        return float(math.sqrt(e2[0])) if len(e2) else math.nan
    return float(math.sqrt(np.trapezoid(e2, t) / span))


@dataclass(frozen=True)
class StepMetrics:
    start: float
    target: float
    overshoot_pct: float
    rise_time_s: float | None
    settling_time_s: float | None     # None: not settled within the record
    steady_state_error: float         # target - mean of the last 10 %
    final_error: float                # target - last sample
    rmse: float                       # eq. (26) of the tracking error
    peak: float                       # the sample furthest in the step's direction
    band: float                       # half-width of the settling band

    def as_dict(self) -> dict[str, float | None]:
        return asdict(self)


def _crossing(t: np.ndarray, progress: np.ndarray, level: float) -> float | None:
    idx = np.nonzero(progress >= level)[0]
    if not idx.size:
        return None
    i = int(idx[0])
    if i == 0:
        return float(t[0])
    p0, p1 = progress[i - 1], progress[i]
    return float(t[i - 1] + (level - p0) / (p1 - p0) * (t[i] - t[i - 1]))


def step_metrics(t: np.ndarray, x: np.ndarray, target: float, start: float = 0.0,
                 setpoint: np.ndarray | None = None, band_frac: float = SETTLE_BAND,
                 band_min: float = 0.0) -> StepMetrics:
    """Metrics of one axis's step response (module docstring).  ``setpoint``
    (the commanded trajectory, same length as x) defaults to the target."""
    t = np.asarray(t, float)
    x = np.asarray(x, float)
    if len(t) != len(x) or len(t) == 0:
        raise ValueError("step metrics need equal, non-empty time and position records")
    step = target - start
    if step == 0:
        raise ValueError("a step of zero has no response to measure")
    s = math.copysign(1.0, step)
    progress = (x - start) / step
    over = float(np.max((x - target) * s))
    band = max(band_frac * abs(step), band_min)
    outside = np.nonzero(np.abs(x - target) > band)[0]
    if not outside.size:
        settle: float | None = float(t[0])
    elif outside[-1] == len(x) - 1:
        settle = None
    else:
        settle = float(t[outside[-1] + 1])
    r10, r90 = _crossing(t, progress, 0.1), _crossing(t, progress, 0.9)
    sp = np.full_like(x, target) if setpoint is None else np.asarray(setpoint, float)
    tail = x[-max(1, int(round(len(x) * TAIL_FRACTION))):]
    return StepMetrics(
        start=float(start), target=float(target),
        overshoot_pct=max(0.0, over) / abs(step) * 100,
        rise_time_s=None if r10 is None or r90 is None else r90 - r10,
        settling_time_s=settle,
        steady_state_error=float(target - tail.mean()),
        final_error=float(target - x[-1]),
        rmse=rmse(t, sp - x),
        peak=float(x[np.argmax((x - start) * s)]),
        band=band,
    )
