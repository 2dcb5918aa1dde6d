# SPDX-License-Identifier: MIT
"""The characterisation method of Lopez-Gomez et al. (2020), section II.B.

Steps as the paper numbers them (1, 3, 4 are bench work; their data arrive
as :class:`~torqueloop.characterize.data.Sweep` objects):

* step 2 - tau_max = r F sin(theta) at nominal voltage, 100 % on;
* step 5 - in the frequency sweep at 50 % duty, the frequencies whose torque
  equals tau_max / 2, interpolated between neighbouring points; ranked, so
  that the loop of step 7 has a "next candidate";
* steps 6-7 - at a candidate, the duty sweep 1-99 % must be linear (fit,
  R^2, worst deviation) with a stable current; the dead zone PW0 is where
  the fitted line leaves zero torque;
* step 8 - is :mod:`torqueloop.characterize.config` (divider count, eq. 4).

The paper states step 7 only as "approximate linear behaviour with a stable
current consumption"; the numbers that make it decidable are
:class:`Thresholds` (defaults documented in docs/characterization.md).
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, field
from typing import Literal, Sequence

import numpy as np

from .data import Sweep


@dataclass(frozen=True)
class LineFit:
    """y = slope * x + intercept by least squares; ``rvalue`` is Pearson's r."""

    slope: float
    intercept: float
    rvalue: float


def line_fit(x: np.ndarray, y: np.ndarray) -> LineFit:
    """The ordinary least-squares line through (x, y) with numpy alone (the
    lab's host install has no scipy); tests/test_characterize.py checks it
    against ``scipy.stats.linregress``."""
    x, y = np.asarray(x, dtype=float), np.asarray(y, dtype=float)
    if x.size < 2 or np.ptp(x) == 0:
        raise MethodError("a line fit needs at least two different duty values")
    a = np.column_stack([x, np.ones_like(x)])
    (slope, icpt), *_ = np.linalg.lstsq(a, y, rcond=None)
    ss_tot = float(np.sum((y - y.mean()) ** 2))
    ss_res = float(np.sum((y - (slope * x + icpt)) ** 2))
    r2 = 0.0 if ss_tot == 0 else max(0.0, 1.0 - ss_res / ss_tot)
    return LineFit(float(slope), float(icpt), float(np.copysign(np.sqrt(r2), slope)))


class MethodError(ValueError):
    """The data are well formed but the method cannot go on (the reason says why)."""


@dataclass(frozen=True)
class Thresholds:
    """The numbers behind the paper's qualitative step 5 and step 7."""

    r2_min: float = 0.98
    """step 7: coefficient of determination of torque vs duty beyond PW0."""
    worst_dev_frac_max: float = 0.05
    """step 7: worst |torque - fitted dead-zone line|, as a fraction of tau_max."""
    current_dev_frac_max: float = 0.10
    """step 7 "stable current": worst |current - its own line vs duty| beyond
    PW0, as a fraction of the largest current in the sweep."""
    current_cv_max: float = 0.10
    """step 7 "stable current": worst current_std_a / current_a beyond PW0
    (checked only when the file records current_std_a)."""
    zero_torque_frac: float = 0.02
    """dead zone: torque below this fraction of tau_max counts as zero."""
    min_moving_points: int = 4
    """steps 6-7: points beyond the dead zone needed for a meaningful fit."""
    step5_nearest_frac: float = 0.05
    """step 5 when no point pair brackets tau_max/2: accept the closest point
    if it is within this fraction of tau_max, else refuse."""
    step5_on_target_frac: float = 0.002
    """step 5: a measured point within this fraction of tau_max of the target
    is *on* it (a force gauge resolves about 0.2 % of its range); a curve
    with no slope above this over the whole sweep is flat."""
    freq_match_frac: float = 0.03
    """a duty sweep belongs to a candidate if its frequency is within this
    fraction (the divider only reaches discrete frequencies: ~1 % apart at 450 Hz)."""

    def as_dict(self) -> dict[str, float | int]:
        return asdict(self)


# ---------------------------------------------------------------- step 2


def tau_max_nm(freq_sweep: Sweep) -> float:
    """Step 2: the torque at nominal voltage, 100 % on (tau = r F sin theta)."""
    if freq_sweep.stall_torque_nm is None:
        raise MethodError(f"{freq_sweep.source}: no step-2 stall measurement")
    return float(freq_sweep.stall_torque_nm)


# ---------------------------------------------------------------- step 5


@dataclass(frozen=True)
class Candidate:
    """A step-5 frequency: where the 50 %-duty torque equals tau_max/2."""

    freq_hz: float
    torque_nm: float
    """torque at freq_hz on the interpolated curve (= target for a crossing)."""
    slope_nm_per_hz: float
    """local d(torque)/d(frequency): the flatter, the less a frequency error matters."""
    kind: Literal["crossing", "on_target", "nearest"]


@dataclass(frozen=True)
class Step5:
    tau_max_nm: float
    target_nm: float
    candidates: tuple[Candidate, ...]
    message: str


def step5_candidates(freq_sweep: Sweep, th: Thresholds = Thresholds()) -> Step5:
    """Step 5: the frequencies whose torque is tau_max * duty (tau_max/2 at the
    paper's 50 %), interpolated linearly between neighbouring points.

    Every crossing is a candidate, interpolated; so is a measured point
    within ``step5_on_target_frac`` of the target where the curve touches
    it without crossing, and, if the whole curve is that close (flat), every
    point.  They are ranked by |slope|
    (flattest first) because there the achieved divider frequency, which
    differs from the chosen one by up to ~0.5 %, changes the torque least;
    slopes too small to matter tie, and ties go to the higher frequency.
    The paper gives no order for its loop back to step 5; this one is ours.
    If nothing crosses, the closest measured point is the only candidate when
    it is within ``step5_nearest_frac`` of tau_max; otherwise MethodError.
    """
    if freq_sweep.kind != "frequency":
        raise MethodError(f"{freq_sweep.source}: step 5 needs a frequency sweep, got a {freq_sweep.kind} sweep")
    tmax = tau_max_nm(freq_sweep)
    duty = freq_sweep.duty_pct if freq_sweep.duty_pct is not None else 50.0
    target = tmax * duty / 100.0
    f, t = freq_sweep.x, freq_sweep.torque_nm
    e = t - target
    grad = np.gradient(t, f)
    tol = th.step5_on_target_frac * tmax
    on = np.abs(e) <= tol
    found: list[Candidate] = []
    if on.all():
        # A flat curve: every point is on the target, none is a better crossing.
        found = [Candidate(float(f[i]), float(t[i]), float(grad[i]), "on_target") for i in range(len(f))]
    else:
        near_crossing = np.zeros(len(f), dtype=bool)
        for i in range(len(f)):
            if e[i] == 0.0:
                found.append(Candidate(float(f[i]), float(t[i]), float(grad[i]), "crossing"))
                near_crossing[i] = True
            elif i + 1 < len(f) and e[i] * e[i + 1] < 0.0:
                s = (t[i + 1] - t[i]) / (f[i + 1] - f[i])
                found.append(Candidate(float(f[i] - e[i] / s), float(target), float(s), "crossing"))
                near_crossing[i] = near_crossing[i + 1] = True
        # points that touch the target without the curve crossing it
        found += [Candidate(float(f[i]), float(t[i]), float(grad[i]), "on_target")
                  for i in range(len(f)) if on[i] and not near_crossing[i]]
    if found:
        # Flattest first.  Slopes that change the torque by less than the
        # on-target tolerance over the whole sweep are all "flat" and tie;
        # ties go to the higher frequency (at stall the current ripple, and
        # with it the torque ripple, shrinks as the period gets shorter
        # against L/R).
        flat = tol / float(f[-1] - f[0])

        def rank(c: Candidate) -> tuple[float, float]:
            m = abs(c.slope_nm_per_hz)
            return (0.0 if m <= flat else m, -c.freq_hz)

        flat_all = bool(on.all())
        found.sort(key=(lambda c: -c.freq_hz) if flat_all else rank)
        n = len(found)
        msg = (
            f"{n} frequenc{'y' if n == 1 else 'ies'} give tau_max*{duty:g}% = {target:.4g} N m; "
            f"first: {found[0].freq_hz:.4g} Hz"
        )
        if flat_all:
            msg += (
                f" (torque does not depend on frequency within {th.step5_on_target_frac:.1%} of tau_max: "
                "step 5 cannot discriminate; the highest frequency is tried first)"
            )
        return Step5(tmax, target, tuple(found), msg)
    k = int(np.argmin(np.abs(e)))
    short = e[k] / tmax
    if abs(short) <= th.step5_nearest_frac:
        c = Candidate(float(f[k]), float(t[k]), float(grad[k]), "nearest")
        msg = (
            f"no frequency crosses {target:.4g} N m; closest is {f[k]:.4g} Hz at {t[k]:.4g} N m "
            f"({short:+.1%} of tau_max, within the {th.step5_nearest_frac:.0%} allowed)"
        )
        return Step5(tmax, target, (c,), msg)
    side = "below" if np.all(e < 0) else "above"
    raise MethodError(
        f"{freq_sweep.source}: step 5: no frequency in {f[0]:g}-{f[-1]:g} Hz reaches tau_max*{duty:g}% = "
        f"{target:.4g} N m (all points {side}; closest {f[k]:g} Hz gives {t[k]:.4g} N m, {short:+.1%} of tau_max, "
        f"more than the {th.step5_nearest_frac:.0%} allowed). Extend the sweep or check the step-2 reading."
    )


# ---------------------------------------------------------------- steps 6-7


@dataclass(frozen=True)
class Check:
    name: str
    value: float
    limit: float
    ok: bool
    text: str


@dataclass(frozen=True)
class Linearity:
    """Steps 6-7 on one duty sweep, and the dead zone PW0."""

    freq_hz: float
    tau_max_nm: float
    pw0_pct: float
    """where the fitted line leaves zero torque (the x-intercept), clipped to 0..100."""
    pw0_raw_pct: float
    """the x-intercept before clipping (negative: torque already at 0 % duty)."""
    pwf_pct: float
    """where the fitted line reaches tau_max (eq. 1's PW_F), at most 100."""
    slope_nm_per_pct: float
    intercept_nm: float
    r2: float
    worst_dev_frac: float
    first_moving_index: int
    checks: tuple[Check, ...]
    source: str = ""

    @property
    def ok(self) -> bool:
        return all(c.ok for c in self.checks)

    @property
    def reasons(self) -> list[str]:
        return [c.text for c in self.checks if not c.ok]

    def model_nm(self, duty_pct: np.ndarray | float) -> np.ndarray:
        """The dead-zone line of eq. (1): zero up to PW0, then linear."""
        d = np.asarray(duty_pct, dtype=float)
        return np.maximum(0.0, self.slope_nm_per_pct * (d - self.pw0_raw_pct))


def steps67_linearity(duty_sweep: Sweep, tau_max: float, th: Thresholds = Thresholds()) -> Linearity:
    """Steps 6-7: fit torque vs duty beyond the dead zone and judge linearity.

    The dead zone ends at the first point whose torque exceeds
    ``zero_torque_frac * tau_max``; a straight line is fitted (least squares)
    to that point and all after it.  PW0 is the line's zero crossing, so that
    eq. (1)'s mapping (zero, then linear from PW0) is the fitted model.
    Checks: R^2, the worst deviation of every point from that model, a
    positive slope, enough points, and the current's stability.
    """
    if duty_sweep.kind != "duty":
        raise MethodError(f"{duty_sweep.source}: steps 6-7 need a duty sweep, got a {duty_sweep.kind} sweep")
    d, t, cur = duty_sweep.x, duty_sweep.torque_nm, duty_sweep.current_a
    zero = th.zero_torque_frac * tau_max
    moving = np.nonzero(t > zero)[0]
    checks: list[Check] = []
    nmov = 0 if moving.size == 0 else len(d) - int(moving[0])
    checks.append(Check(
        "moving_points", nmov, th.min_moving_points, nmov >= th.min_moving_points,
        f"{nmov} points beyond the dead zone (torque > {zero:.3g} N m), need {th.min_moving_points}",
    ))
    if nmov < th.min_moving_points:
        nan = float("nan")
        return Linearity(
            float(duty_sweep.freq_hz or nan), tau_max, nan, nan, nan, nan, nan, nan, nan,
            len(d), tuple(checks), duty_sweep.source,
        )
    k0 = int(moving[0])
    dm, tm = d[k0:], t[k0:]
    fit = line_fit(dm, tm)
    slope, icpt = float(fit.slope), float(fit.intercept)
    r2 = float(fit.rvalue) ** 2
    checks.append(Check(
        "slope", slope, 0.0, slope > 0,
        f"torque rises with duty at {slope:.4g} N m per %" if slope > 0 else
        f"torque does not rise with duty (slope {slope:.3g} N m per %)",
    ))
    pw0_raw = -icpt / slope if slope > 0 else float("nan")
    pw0 = float(np.clip(pw0_raw, 0.0, 100.0)) if slope > 0 else float("nan")
    pwf = float(min(100.0, pw0_raw + tau_max / slope)) if slope > 0 else float("nan")
    model = np.maximum(0.0, slope * (d - pw0_raw)) if slope > 0 else np.full_like(d, icpt)
    dev = np.abs(t - model) / tau_max
    worst = float(dev.max())
    iw = int(dev.argmax())
    checks.append(Check(
        "r2", r2, th.r2_min, r2 >= th.r2_min,
        f"R^2 = {r2:.4f} (need >= {th.r2_min:g})",
    ))
    checks.append(Check(
        "worst_dev_frac", worst, th.worst_dev_frac_max, worst <= th.worst_dev_frac_max,
        f"worst deviation from the dead-zone line {worst:.1%} of tau_max at {d[iw]:g} % duty "
        f"(allowed {th.worst_dev_frac_max:.0%})",
    ))
    # Stable current (the paper's other step-7 condition).  At stall the
    # current follows the mean bridge voltage, so beyond the dead zone it
    # should sit on a line as well; a drifting or jumping current shows up
    # as deviation from that line.
    cm = cur[k0:]
    cfit = line_fit(dm, cm)
    cscale = float(cur.max()) if cur.max() > 0 else 1.0
    cdev = float(np.max(np.abs(cm - (cfit.intercept + cfit.slope * dm))) / cscale)
    checks.append(Check(
        "current_dev_frac", cdev, th.current_dev_frac_max, cdev <= th.current_dev_frac_max,
        f"current deviates {cdev:.1%} of its maximum from a line in duty "
        f"(allowed {th.current_dev_frac_max:.0%})",
    ))
    if duty_sweep.current_std_a is not None:
        cs = duty_sweep.current_std_a[k0:]
        with np.errstate(divide="ignore", invalid="ignore"):
            cv = np.where(cm > 0, cs / np.where(cm > 0, cm, 1.0), np.where(cs > 0, np.inf, 0.0))
        wcv = float(cv.max())
        checks.append(Check(
            "current_cv", wcv, th.current_cv_max, wcv <= th.current_cv_max,
            f"current wanders up to {wcv:.1%} (std/mean) at one point (allowed {th.current_cv_max:.0%})",
        ))
    return Linearity(
        freq_hz=float(duty_sweep.freq_hz) if duty_sweep.freq_hz is not None else float("nan"),
        tau_max_nm=tau_max, pw0_pct=pw0, pw0_raw_pct=float(pw0_raw), pwf_pct=pwf,
        slope_nm_per_pct=slope, intercept_nm=icpt, r2=r2, worst_dev_frac=worst,
        first_moving_index=k0, checks=tuple(checks), source=duty_sweep.source,
    )


# ---------------------------------------------------------------- the loop


@dataclass(frozen=True)
class Attempt:
    candidate: Candidate
    duty_sweep: Sweep | None
    linearity: Linearity | None


@dataclass(frozen=True)
class MotorResult:
    """The method's outcome for one motor.

    ``status``: ``"pass"`` (``chosen`` and ``linearity`` set: go to step 8);
    ``"need_duty_sweep"`` (record a duty sweep at ``next_freq_hz`` and run
    again); ``"fail"`` (every candidate failed step 7).
    """

    status: Literal["pass", "need_duty_sweep", "fail"]
    freq_sweep: Sweep
    step5: Step5
    attempts: tuple[Attempt, ...]
    chosen: Candidate | None = None
    linearity: Linearity | None = None
    duty_sweep: Sweep | None = None
    next_freq_hz: float | None = None
    unused_duty_sweeps: tuple[str, ...] = field(default_factory=tuple)
    message: str = ""


def _match(c: Candidate, duty_sweeps: Sequence[Sweep], th: Thresholds) -> Sweep | None:
    best: tuple[float, Sweep] | None = None
    for s in duty_sweeps:
        assert s.freq_hz is not None
        rel = abs(s.freq_hz - c.freq_hz) / c.freq_hz
        if rel <= th.freq_match_frac and (best is None or rel < best[0]):
            best = (rel, s)
    return None if best is None else best[1]


def characterize_motor(
    freq_sweep: Sweep, duty_sweeps: Sequence[Sweep], th: Thresholds = Thresholds()
) -> MotorResult:
    """Steps 2-7 with the paper's loop: candidates in step-5 order; the first
    whose duty sweep passes step 7 is chosen.  A candidate with no duty sweep
    recorded stops the loop and asks for one (the lab measures, then reruns)."""
    for s in duty_sweeps:
        if s.kind != "duty":
            raise MethodError(f"{s.source}: expected a duty sweep, got a {s.kind} sweep")
        if not s.bench.matches(freq_sweep.bench):
            raise MethodError(
                f"{s.source}: bench constants (r, theta, supply) differ from {freq_sweep.source}; "
                "both sweeps must come from the same set-up"
            )
    s5 = step5_candidates(freq_sweep, th)
    tmax = s5.tau_max_nm
    attempts: list[Attempt] = []
    used: set[str] = set()

    def unused() -> tuple[str, ...]:
        return tuple(s.source for s in duty_sweeps if s.source not in used)

    for c in s5.candidates:
        ds = _match(c, duty_sweeps, th)
        if ds is None:
            attempts.append(Attempt(c, None, None))
            return MotorResult(
                "need_duty_sweep", freq_sweep, s5, tuple(attempts), next_freq_hz=c.freq_hz,
                unused_duty_sweeps=unused(),
                message=(
                    f"step 6: record a duty sweep (1-99 %) at {c.freq_hz:.4g} Hz "
                    f"(within {th.freq_match_frac:.0%}), then run again"
                ),
            )
        used.add(ds.source)
        lin = steps67_linearity(ds, tmax, th)
        attempts.append(Attempt(c, ds, lin))
        if lin.ok:
            return MotorResult(
                "pass", freq_sweep, s5, tuple(attempts), chosen=c, linearity=lin, duty_sweep=ds,
                unused_duty_sweeps=unused(),
                message=f"step 7 passed at {c.freq_hz:.4g} Hz: PW0 = {lin.pw0_pct:.2f} %, R^2 = {lin.r2:.4f}",
            )
    fails = "; ".join(
        f"{a.candidate.freq_hz:.4g} Hz: {', '.join(a.linearity.reasons)}" for a in attempts if a.linearity
    )
    return MotorResult(
        "fail", freq_sweep, s5, tuple(attempts), unused_duty_sweeps=unused(),
        message=f"step 7 failed at every step-5 candidate ({fails})",
    )


# ---------------------------------------------------------------- the paper's dead zone


@dataclass(frozen=True)
class MotionDeadZone:
    """The dead zone as the paper measures it (sec. II.B): on the applied
    system, the pulse width raised until the system moves, then lowered
    until it stops moving; one direction at one carrier.  Beside it, the
    project's intercept PW0 (:class:`Linearity`) is where the stalled torque
    line leaves zero: a different quantity (a torque threshold on the held
    motor, not a motion threshold on the free one)."""

    freq_hz: float
    direction: int
    start_pct: float
    """the first duty of the rising ramp at which the system moved (breakaway)."""
    stop_pct: float
    """the lowest duty of the falling ramp at which it still moved; one step
    lower it stopped.  The paper's procedure ends here, so this is its PW0."""
    threshold_counts: float
    """motion: at least this many encoder counts moved in one dwell."""

    @property
    def pw0_pct(self) -> float:
        return self.stop_pct

    @property
    def hysteresis_pct(self) -> float:
        """start - stop: how far the breakaway lies above the stop."""
        return self.start_pct - self.stop_pct


def motion_dead_zone(duty_up_pct: Sequence[float], moved_up: Sequence[float], duty_down_pct: Sequence[float],
                     moved_down: Sequence[float], threshold_counts: float, freq_hz: float,
                     direction: int) -> MotionDeadZone:
    """The paper's dead zone from a recorded ramp: ``moved_up[k]`` is the
    motion (encoder counts, either sign) during the dwell at the rising
    ramp's ``duty_up_pct[k]``, ``moved_down`` the same for the falling ramp
    that follows it.  Motion is ``|moved| >= threshold_counts``."""
    up = [(float(d), abs(float(m)) >= threshold_counts) for d, m in zip(duty_up_pct, moved_up, strict=True)]
    down = [(float(d), abs(float(m)) >= threshold_counts) for d, m in zip(duty_down_pct, moved_down, strict=True)]
    if any(b[0] <= a[0] for a, b in zip(up, up[1:])) or any(b[0] >= a[0] for a, b in zip(down, down[1:])):
        raise MethodError("dead zone ramp: the rising ramp must rise and the falling ramp fall")
    start = next((d for d, mv in up if mv), None)
    if start is None:
        top = up[-1][0] if up else float("nan")
        raise MethodError(f"dead zone ramp: the system never moved up to {top:g} % duty "
                          f"({threshold_counts:g} counts per dwell); raise the ramp further")
    last_moving = start
    for d, mv in down:
        if d > start:
            raise MethodError("dead zone ramp: the falling ramp must start below the breakaway")
        if not mv:
            return MotionDeadZone(freq_hz, direction, start, last_moving, threshold_counts)
        last_moving = d
    raise MethodError(f"dead zone ramp: the system still moved at {last_moving:g} % duty; lower the ramp further")
