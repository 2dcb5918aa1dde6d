# SPDX-License-Identifier: MIT
"""``torqueloop tune``: gains for an axis from its identified plant, the
board settings that carry them, and writing them to a board.

The design is torqueloop/host/tunedesign.py's (poles, margins, stiction,
the predicted step); this module turns a :class:`~.tunedesign.Design` into
the firmware's raw parameters (protocol.toml: LAW, KP_Q16, KD_Q16, KI_Q16
in PWM steps per count, per count/s and per count s, q16; PW0 in PWM ticks;
FDIV for the carrier; VEL_MODE, the speed the derivative is taken on;
FC_POS, FC_NEG, IZONE_Q16, the friction compensation; KVFF_Q16, KAFF_Q16, the
feed-forward on trapezoid moves; PERIOD_US,
the control period the design was discretised at) and writes them through the normal client, refusing while
the axis moves.  The verification on the fast model and on the RTL board
image is torqueloop/sim/tuneverify.py's (it needs the simulation stack).
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass
from typing import Any

from torqueloop.host.client import Client, ProtocolError
from torqueloop.host.tunedesign import (TIGHT_BAND_COUNTS, AxisModel, Design, Wish, design, predict,
                                        predict_following, verify_profile)
from torqueloop.spec import protocol as P
from torqueloop.spec.metrics import StepMetrics, step_metrics
from torqueloop.spec.pwm import carrier_hz, full_scale
from torqueloop.spec.system import SYSTEM

LAW_CODE = {"pd": 2, "pid": 3}
#: the speed the derivative is taken on: 0, the Euler difference averaged over two periods (a period's
#: lag, a few degrees at these loops' crossover).  Not 1, the edge-timestamp speed: at rest near the
#: target it is one count over the last edge's interval, and with z's Kd (1.2 steps per count/s on the
#: scaled lab plant) every single edge put 100-200 steps on the command, which kicked the rotor and kept
#: it hunting between -1 and -2 counts (settled into +-2 counts at 4.0 s, against 2.4 s with 0)
VEL_MODE = 0
#: the PID's real pole at alpha wn (tunedesign's alpha), the candidates from fast to slow: a fast integral
#: returns the overshoot its windup causes sooner, a slow one winds up less; tune_axis keeps the one whose
#: predicted one-turn step settles into the tolerance first within the overshoot limit and the board's gains
PID_ALPHAS = (1.0, 0.7, 0.5, 0.35, 0.25)
#: the PID's damping candidates beyond the overshoot limit's (None): a saturated one-turn step overshoots
#: by how late the loop starts braking, and more damping (more Kd against Kp) brakes earlier
PID_ZETAS = (None, 1.3, 1.6, 2.0)
#: the design model's record the candidates are compared on (s): long enough for the slowest to settle,
#: whatever record the prediction is then reported over
CHOOSE_S = 6.0
#: the keys of the identified axis the design reads (plant file, [identifiable.<axis>])
NEEDED = ("speed_gain_rad_per_s_per_v", "time_constant_s", "friction_v_pos", "friction_v_neg",
          "dead_zone_pos_pct", "dead_zone_neg_pct")


class TuneError(ProtocolError):
    """The design or its application cannot go on; one line."""


@dataclass(frozen=True)
class AxisTune:
    axis: int
    name: str
    model: AxisModel
    design: Design
    fdiv: int
    predicted: StepMetrics
    step_counts: int
    predicted_tight_s: float | None = None    # the design model's settling into +-TIGHT_BAND_COUNTS
    trapezoid: tuple[int, int] = (0, 0)       # VMAX, AMAX of the move the feed-forward is verified on
    #: the design model's peak following error on that move (counts), with and without the feed-forward
    predicted_following: tuple[float, float] = (math.nan, math.nan)
    predicted_trapezoid: StepMetrics | None = None     # the design model's metrics of that move (feed-forward on)
    predicted_trapezoid_tight_s: float | None = None

    @property
    def carrier_hz(self) -> float:
        return carrier_hz(self.fdiv)

    def settings(self) -> dict[str, int]:
        """The axis's raw parameters (protocol.toml names), in the order they are written."""
        return {"FDIV": self.fdiv, "PW0": self.design.pw0, "LAW": LAW_CODE[self.design.law],
                **self.design.q16(), "VEL_MODE": VEL_MODE, **self.design.compensation(), **self.design.feedforward()}

    def as_dict(self) -> dict[str, Any]:
        d = self.design
        p = self.predicted
        return {"axis": self.axis, "name": self.name, "law": d.law, "settings": self.settings(),
                "period_us": round(d.period_s * 1e6), "carrier_hz": self.carrier_hz,
                "kp_steps_per_count": d.kp, "kd_steps_per_count_per_s": d.kd, "ki_steps_per_count_s": d.ki,
                "wn_rad_s": d.wn, "zeta": d.zeta, "gain_margin_db": d.gain_margin_db,
                "phase_margin_deg": d.phase_margin_deg, "stick_band_counts": d.stick_band_counts,
                "pid_pole_alpha": d.alpha, "fc_steps": {"pos": d.fc[0], "neg": d.fc[1]},
                "hunting_guard_counts": d.izone_counts,
                "feedforward": {"kvff_steps_per_count_per_s": d.kvff, "kaff_steps_per_count_per_s2": d.kaff},
                "verify_trapezoid": {"VMAX": self.trapezoid[0], "AMAX": self.trapezoid[1]},
                "notes": list(d.notes), "step_counts": self.step_counts,
                "predicted": {"overshoot_pct": p.overshoot_pct, "settling_time_s": p.settling_time_s,
                              "settling_time_2_counts_s": self.predicted_tight_s,
                              "steady_state_error_counts": p.steady_state_error},
                "predicted_trapezoid": None if (q := self.predicted_trapezoid) is None else {
                    "overshoot_pct": q.overshoot_pct, "settling_time_s": q.settling_time_s,
                    "settling_time_2_counts_s": self.predicted_trapezoid_tight_s,
                    "steady_state_error_counts": q.steady_state_error,
                    "peak_following_error_counts": self.predicted_following[0],
                    "peak_following_error_without_feedforward_counts": self.predicted_following[1]}}


def divider_at_least(f_hz: float) -> int:
    """FDIV of the lowest carrier the divider makes at or above ``f_hz`` (eq. 4), within the bridge's rating."""
    fdiv = max(1, math.floor(SYSTEM.clk_hz / (f_hz * full_scale())))
    if carrier_hz(fdiv) > SYSTEM.bridge_max_hz:
        raise TuneError(f"--pwm-freq {f_hz:g} Hz: the divider's carrier at or above it, {carrier_hz(fdiv):.0f} Hz, "
                        f"is beyond the bridge's {SYSTEM.bridge_max_hz} Hz")
    return fdiv


def axis_model(ident: dict[str, float], where: str, supply_v: float) -> AxisModel:
    """The identified axis from a plant file's keys; a missing or non-physical one in one line."""
    for k in NEEDED:
        v = ident.get(k)
        if not isinstance(v, (int, float)) or v != v:
            raise TuneError(f"{where}: {k} missing (run `torqueloop identify --out` or `plant export`)")
    if ident["speed_gain_rad_per_s_per_v"] <= 0 or ident["time_constant_s"] <= 0:
        raise TuneError(f"{where}: speed_gain_rad_per_s_per_v and time_constant_s must be positive")
    return AxisModel.from_identified(ident, supply_v)


def _tight(times, xs, target: float, band: float) -> float | None:
    return step_metrics(times, xs, target, band_frac=0.0, band_min=band).settling_time_s


def tune_axis(axis: int, ident: dict[str, float], wish: Wish, pwm_hz: float, where: str, supply_v: float = 12.0,
              step_counts: int = SYSTEM.counts_per_turn, predict_s: float = 3.0) -> AxisTune:
    """The axis's design for ``wish``; a PID's damping and integral pole are
    chosen from PID_ZETAS x PID_ALPHAS on the design model's one-turn step
    (within the overshoot limit, then the earliest settling into the wish's
    tolerance), among the designs whose gains the board holds."""
    m = axis_model(ident, where, supply_v)
    top = P.gain_raw_from_phys(P.PARAMS["KP_UNM_RAD"].max, SYSTEM.axes[axis].tau_max_mnm, SYSTEM.counts_per_turn)
    best, refused = None, None
    pid = wish.law == "pid"
    for zeta, alpha in itertools.product(PID_ZETAS if pid else (None,), PID_ALPHAS if pid else (1.0,)):
        d = design(m, wish, alpha=alpha, zeta=zeta)
        over = [(k, v) for k, v in d.q16().items() if v > top]
        if over:
            refused = refused or over[0]
            continue
        ts, xs, met = predict(m, d, step_counts, max(predict_s, CHOOSE_S), wish.cmd_limit)
        tol = _tight(ts, xs, step_counts, wish.tolerance_counts)
        rank = (met.overshoot_pct > wish.overshoot_pct, met.overshoot_pct if met.overshoot_pct > wish.overshoot_pct
                else 0.0, math.inf if tol is None else tol)
        if best is None or rank < best[0]:
            best = (rank, d)
    if best is None:
        k, v = refused  # type: ignore[misc]
        raise TuneError(f"axis {axis}: {k} = {v} is beyond what the board holds ({top}: "
                        f"{P.PARAMS['KP_UNM_RAD'].max / 1e6:g} N m/rad at its tau_max): ask for a slower settling")
    d = best[1]
    ts, xs, met = predict(m, d, step_counts, predict_s, wish.cmd_limit)     # over the record asked for
    tight = _tight(ts, xs, step_counts, TIGHT_BAND_COUNTS)
    trap = verify_profile(m, d, wish.cmd_limit)
    peak, ts, xs = predict_following(m, d, step_counts, *trap, predict_s, wish.cmd_limit)
    peak_off = predict_following(m, d, step_counts, *trap, predict_s, wish.cmd_limit, feedforward=False)[0]
    return AxisTune(axis, SYSTEM.axes[axis].name, m, d, divider_at_least(pwm_hz), met, step_counts, tight, trap,
                    (peak, peak_off), step_metrics(ts, xs, step_counts), _tight(ts, xs, step_counts, TIGHT_BAND_COUNTS))


def check_margins(t: AxisTune, min_gm_db: float, min_pm_deg: float) -> str | None:
    """None when the design keeps the margins asked for, else what it misses (one line)."""
    d = t.design
    if d.gain_margin_db < min_gm_db or d.phase_margin_deg < min_pm_deg:
        return (f"axis {t.axis}: the design keeps a gain margin of {d.gain_margin_db:.1f} dB and a phase margin of "
                f"{d.phase_margin_deg:.0f} deg, asked {min_gm_db:g} dB and {min_pm_deg:g} deg: ask for a slower "
                "settling or a shorter period")
    return None


def apply(c: Client, tunes: list[AxisTune], save: bool) -> dict[str, Any]:
    """Write the tuned settings to the board and read them back; ``save``
    stores them (the board's parameter store, every axis disabled).  Refused
    while an axis being tuned moves; PERIOD_US is the board's (both axes)."""
    period = {round(t.design.period_s * 1e6) for t in tunes}
    if len(period) != 1:
        raise TuneError("the axes were designed at different control periods")
    period_us = period.pop()
    for t in tunes:
        s = c.status(t.axis)
        if s["moving"] or (s["enabled"] and s["velocity_q8"] != 0):
            raise TuneError(f"axis {t.axis} is moving: wait until it stands, or `torqueloop stop`")
    if save:
        for a in range(P.AXIS_COUNT):
            if c.status(a)["enabled"]:
                raise TuneError(f"--save stores with every axis disabled and axis {a} is enabled: "
                                "`torqueloop disable --all` first")
    c.set_param("PERIOD_US", period_us)
    back: dict[str, dict[str, int]] = {}
    for t in tunes:
        for k, v in t.settings().items():
            c.set_param(k, v, t.axis)
        back[t.name] = {k: c.get_param(k, t.axis) for k in t.settings()}
        if back[t.name] != t.settings():
            raise TuneError(f"axis {t.axis}: the board reads back {back[t.name]}, not {t.settings()}")
    out: dict[str, Any] = {"period_us": c.get_param("PERIOD_US"), "read_back": back}
    if save:
        out["store"] = c.save()
    return out
