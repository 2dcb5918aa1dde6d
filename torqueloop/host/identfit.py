# SPDX-License-Identifier: MIT
"""Fits of an encoder-only identification: the numbers behind
``torqueloop identify``, from the traces an open-loop drive records.

The model is the averaged armature of sim_models/identifiable.py (the
closed form the plant file's ``[identifiable.<axis>]`` section holds), per
direction of motion, with d the duty (fraction), V_s the supply:

    driven    J w' = (k/R) (d V_s - k w - V_b) - T_f - b w  ->  w_ss = K (d V_s - V_f),  w' = (w_ss - w) / tau
    coasting  J w' = -T_f - b w                                (the bridge off: no current below V_s)

so a duty staircase gives K and V_f (a line), the rise after each step tau
(an exponential), and a coast-down T_f / J and b / J (a line in w).  With
the loop resistance R, which an encoder cannot see (a meter can):

    K = k / (k^2 + R b),  tau = J R / (k^2 + R b),  b = beta J
    =>  J = tau k / (K R),  k = (1 - beta tau) / K,  T_f = a_c J,  V_b = V_f - R T_f / k

(k = k_e = k_t in SI).  Every estimate carries a standard error from its
least-squares fit (``<key>_sigma``): the scatter of the readings about the
model, not the model's own error.  numpy only: this runs on a lab laptop
with the host install.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Line:
    """y = slope x + intercept, with standard errors from the residuals."""

    slope: float
    intercept: float
    slope_sigma: float
    intercept_sigma: float
    n: int

    def at(self, x: float) -> float:
        return self.slope * x + self.intercept

    @property
    def root(self) -> float:
        """x where the line crosses zero."""
        return -self.intercept / self.slope


def fit_line(x, y) -> Line:
    """Ordinary least squares with the textbook covariance s^2 (A^T A)^-1
    (numpy's lstsq; the same numbers as scipy.stats.linregress)."""
    x = np.asarray(x, dtype=float)
    y = np.asarray(y, dtype=float)
    if x.shape != y.shape or x.size < 2:
        raise ValueError(f"a line needs at least two points of x and y (got {x.size} and {y.size})")
    if np.ptp(x) == 0:
        raise ValueError("a line needs two different x values")
    a = np.column_stack([x, np.ones_like(x)])
    coef, *_ = np.linalg.lstsq(a, y, rcond=None)
    dof = x.size - 2
    s2 = float(np.sum((y - a @ coef) ** 2) / dof) if dof > 0 else 0.0
    cov = s2 * np.linalg.inv(a.T @ a)
    return Line(float(coef[0]), float(coef[1]), math.sqrt(cov[0, 0]), math.sqrt(cov[1, 1]), int(x.size))


@dataclass(frozen=True)
class Exponential:
    """w(t) = final + (start - final) exp(-t / tau), t from the step."""

    tau: float
    final: float
    start: float
    tau_sigma: float


def fit_exponential(t, w, tau_lo: float, tau_hi: float) -> Exponential:
    """The first-order response through a trace: for each tau the amplitude
    and the final value are linear, so tau is found by a bracketed search
    (golden section on the residual, which is unimodal for a first-order
    trace) and the rest by least squares.  The standard error of tau is
    from the curvature of the residual at the minimum."""
    t = np.asarray(t, dtype=float) - float(t[0])
    w = np.asarray(w, dtype=float)
    if t.size < 4:
        raise ValueError("an exponential needs at least four samples")

    def solve(tau: float) -> tuple[float, np.ndarray]:
        e = np.exp(-t / tau)
        a = np.column_stack([1.0 - e, e])             # final (1 - e) + start e
        coef, *_ = np.linalg.lstsq(a, w, rcond=None)
        return float(np.sum((w - a @ coef) ** 2)), coef

    lo, hi = math.log(tau_lo), math.log(tau_hi)
    g = (math.sqrt(5) - 1) / 2
    c, d = hi - g * (hi - lo), lo + g * (hi - lo)
    fc, fd = solve(math.exp(c))[0], solve(math.exp(d))[0]
    for _ in range(80):
        if fc < fd:
            hi, d, fd = d, c, fc
            c = hi - g * (hi - lo)
            fc = solve(math.exp(c))[0]
        else:
            lo, c, fc = c, d, fd
            d = lo + g * (hi - lo)
            fd = solve(math.exp(d))[0]
    tau = math.exp((lo + hi) / 2)
    rss, coef = solve(tau)
    h = tau * 1e-3
    curv = (solve(tau + h)[0] - 2 * rss + solve(tau - h)[0]) / h**2
    s2 = rss / max(1, t.size - 3)
    sigma = math.sqrt(2 * s2 / curv) if curv > 0 else math.inf
    return Exponential(tau, float(coef[0]), float(coef[1]), sigma)


@dataclass(frozen=True)
class Direction:
    """One direction's readings: a duty staircase's steady speeds, the rise
    time constants at its steps and a coast-down line."""

    speed_line: Line            # w_ss (rad/s, motor) against applied volts d V_s
    tau: float                  # mean of the steps' time constants (s)
    tau_sigma: float
    coast: Line | None          # w' (rad/s^2) against w (rad/s) while coasting, w > 0 side taken as |w|
    breakaway_pct: float        # duty where the rotor broke away from rest (raise until it moves)
    stop_pct: float             # duty where it stopped again (lower until it stops)


def estimates(pos: Direction, neg: Direction, resistance_ohm: float | None) -> dict[str, float]:
    """The plant file's ``[identifiable.<axis>]`` keys (and ``<key>_sigma``)
    from both directions' readings; the physical ones only with R."""
    out: dict[str, float] = {}
    k_gain = (pos.speed_line.slope + neg.speed_line.slope) / 2
    out["speed_gain_rad_per_s_per_v"] = k_gain
    out["speed_gain_rad_per_s_per_v_sigma"] = math.hypot(pos.speed_line.slope_sigma, neg.speed_line.slope_sigma) / 2
    tau = (pos.tau + neg.tau) / 2
    out["time_constant_s"] = tau
    out["time_constant_s_sigma"] = math.hypot(pos.tau_sigma, neg.tau_sigma) / 2
    for name, d in (("pos", pos), ("neg", neg)):
        ln = d.speed_line
        out[f"friction_v_{name}"] = ln.root
        # error of the root x0 = -c / m: first-order propagation (slope and intercept taken independent)
        out[f"friction_v_{name}_sigma"] = math.hypot(ln.intercept_sigma / ln.slope,
                                                     ln.intercept * ln.slope_sigma / ln.slope**2)
        out[f"dead_zone_{name}_pct"] = d.breakaway_pct
        out[f"stop_duty_{name}_pct"] = d.stop_pct
    if resistance_ohm is None:
        return out
    r = resistance_ohm
    betas = [d.coast.slope for d in (pos, neg) if d.coast is not None]
    beta = -float(np.mean(betas)) if betas else 0.0          # w' = -beta w - a_c
    k = (1.0 - beta * tau) / k_gain
    j = tau * k / (k_gain * r)
    out["back_emf_v_s_per_rad"] = k
    out["back_emf_v_s_per_rad_sigma"] = k * out["speed_gain_rad_per_s_per_v_sigma"] / k_gain
    out["inertia_at_motor_kg_m2"] = j
    out["inertia_at_motor_kg_m2_sigma"] = j * math.hypot(out["time_constant_s_sigma"] / tau,
                                                         2 * out["speed_gain_rad_per_s_per_v_sigma"] / k_gain)
    out["viscous_n_m_s_per_rad"] = beta * j
    for name, d in (("pos", pos), ("neg", neg)):
        if d.coast is not None:
            t_f = -d.coast.intercept * j
            t_f_sigma = abs(t_f) * math.hypot(d.coast.intercept_sigma / d.coast.intercept,
                                              out["inertia_at_motor_kg_m2_sigma"] / j)
        else:       # no coast-down: the friction voltage is all friction (no brush drop separated)
            t_f = k * out[f"friction_v_{name}"] / r
            t_f_sigma = k * out[f"friction_v_{name}_sigma"] / r
        out[f"coulomb_{name}_n_m"] = t_f
        out[f"coulomb_{name}_n_m_sigma"] = t_f_sigma
        out[f"brush_drop_{name}_v"] = out[f"friction_v_{name}"] - r * t_f / k
    return out


def bisect_threshold(moves, lo: float, hi: float, resolution: float) -> float:
    """The smallest duty (fraction, > 0) at which ``moves(duty)`` is true, to
    within ``resolution``: the paper's dead zone, "raise the pulse until the
    system moves", found by bisection (each probe starts from rest, so
    stiction is met afresh).  ``moves(hi)`` must be true and ``moves(lo)``
    false; a rig where ``hi`` does not move raises ValueError."""
    if not moves(hi):
        raise ValueError(f"no motion at {100 * hi:.1f} % duty: check the wiring, the arm switch and cmd_limit")
    while hi - lo > resolution:
        mid = (lo + hi) / 2
        if moves(mid):
            hi = mid
        else:
            lo = mid
    return hi
