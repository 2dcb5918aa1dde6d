"""Pure-model closed loop: the paper's P, PD and PID laws (eq 20-22) with the
Table 1 gains, sampled like the firmware, driving the plant through PWM.

Interpretation of Table 1 (docs/plant.md): the "Given value" column is the
gain in physical units, torque at the output shaft per radian of screw-angle
error (N m/rad), per rad/s (N m s/rad) and per rad s (N m/(rad s)); the
controller's torque command is turned into a duty cycle by dividing by the
paper's tau_max (2.4 N m, 2.08 N m: twice the tau_max/2 of sec. VI.A), which
is what the "Pulse-Width (%)" column approximately is (0.82 / 2.4 = 34 %,
0.96 / 2.08 = 46 %).  The "Total bits used" column is not used.

Per sample period T_s (25 ms, the paper's speed sample period):
position x_k from the encoder count (8400 counts per screw turn),
speed v_k = a (x_k - x_{k-1}) / T_s + (1 - a) v_{k-1} (filtered Euler),
tau = K_p e + K_d (-v) + K_i sum(e T_s), saturation eq (19), dead-zone
compensation eq (1) (PW0, default 0) and 10-bit quantisation; the PWM block
loads the new duty at its next period start (double buffering) and a
command c is c/1023 of its period, as pwm_torque's.  The integral has the
firmware's anti-windup (held while the output saturates in the error's
direction, its term kept within full scale; ``anti_windup=False`` for the
plain eq. (22) sum), so that RTL-in-the-loop and this loop run one law.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Sequence

import numpy as np

from sim_models.bridge import Pins
from sim_models.params import PlantParams, load_params
from sim_models.stepper import TwoAxisPlant


@dataclass(frozen=True)
class Gains:
    kp: float            # N m / rad
    kd: float = 0.0      # N m s / rad
    ki: float = 0.0      # N m / (rad s)


# Table 1, "Given value" column: (axis x, axis z)
TABLE1: dict[str, tuple[Gains, Gains]] = {
    "P": (Gains(0.820), Gains(0.960)),
    "PD": (Gains(0.650, kd=0.450), Gains(0.750, kd=0.250)),
    "PID": (Gains(0.455, kd=0.366, ki=0.155), Gains(0.570, kd=0.430, ki=0.220)),
}


@dataclass(frozen=True)
class LoopConfig:
    setpoint_rad: float = 6.28          # one screw turn = 4 mm (sec. VI.B)
    t_end_s: float = 40.0               # T of eq (26)
    sample_s: float = 0.025             # 2.5e-2 s (sec. VI.B)
    vel_filter: float = 0.5             # weight of the new Euler difference
    pwm_bits: int = 10                  # gamma = 2^10 (eq 2)
    clk_hz: float = 50e6                # PWM edges fall on the FPGA clock
    pw0: float = 0.0                    # dead zone of eq (1), fraction of full scale
    drive: str = "brake"                # off-phase: "brake" (slow decay) or "coast"
    pwm_hz: tuple[float, float] = (450.0, 200.0)
    gains: tuple[Gains, Gains] = field(default_factory=lambda: TABLE1["P"])
    # Integrator held while the output is saturated in the direction the error
    # pushes, and its term kept within full scale: what the firmware does
    # (docs/firmware.md).  False gives the plain eq. (22) integral.
    anti_windup: bool = True


@dataclass
class LoopResult:
    t: np.ndarray              # sample times (s)
    x_meas: np.ndarray         # (n, 2) screw angle from the encoder (rad)
    x_true: np.ndarray         # (n, 2) screw angle of the model (rad)
    table_mm: np.ndarray       # (n, 2)
    v_est: np.ndarray          # (n, 2) filtered speed estimate (rad/s)
    duty: np.ndarray           # (n, 2) signed duty applied (fraction)
    current: np.ndarray        # (n, 2) armature current at the sample (A)
    wall_s: float = 0.0
    calls: int = 0


def duty_from_torque(tau: float, tau_max: float, cfg: LoopConfig) -> int:
    """Signed PWM count: saturation eq (19), dead-zone compensation eq (1)."""
    full = (1 << cfg.pwm_bits) - 1
    u = max(-1.0, min(1.0, tau / tau_max))
    if u == 0.0:
        return 0
    mag = cfg.pw0 + (1.0 - cfg.pw0) * abs(u)
    return int(math.copysign(min(full, round(mag * full)), u))


def _pins(count: int, on: bool, drive: str) -> Pins:
    if count == 0 or not on:
        return Pins(0, 0, 1, 1) if drive == "brake" else Pins(0, 0, 0, 0)
    return Pins(1, 0, 1, 1) if count > 0 else Pins(0, 1, 1, 1)


def run_loop(cfg: LoopConfig, params: PlantParams | None = None,
             plant: TwoAxisPlant | None = None, progress: bool = False) -> LoopResult:
    """Step both axes to ``setpoint_rad`` from rest and record every sample."""
    import time
    params = params or load_params()
    plant = plant or TwoAxisPlant(params, seed=0)
    tick = 1.0 / cfg.clk_hz
    # pwm_torque's period is 2^N - 1 ticks and a command c is c ticks of it
    # (docs/pwm_torque.md), so the duty is c / 1023, not c / 1024.
    full = (1 << cfg.pwm_bits) - 1
    period_ticks = [round(cfg.clk_hz / f) for f in cfg.pwm_hz]
    counts_per_rad = params.encoder.counts_per_motor_rev * params.axes[0].gear_ratio / (2 * math.pi)
    tau_max = [a.tau_max_paper_N_m for a in params.axes]
    n_samples = int(round(cfg.t_end_s / cfg.sample_s)) + 1
    sample_ticks = round(cfg.sample_s * cfg.clk_hz)
    res = LoopResult(*(np.zeros((n_samples, 2)) if k else np.zeros(n_samples) for k in range(7)))
    pending = [0, 0]         # duty loaded at the next period start
    active = [0, 0]
    pins: list[Pins] = [_pins(0, False, cfg.drive)] * 2
    next_start = [0, 0]      # tick of each axis's next period start
    next_off: list[int | None] = [None, None]
    x_prev = [0.0, 0.0]
    v = [0.0, 0.0]
    integ = [0.0, 0.0]
    sat_sign = [0, 0]        # sign of the last output's saturation (0: none)
    now = 0
    t0 = time.monotonic()
    calls = 0
    for k in range(n_samples):
        ts = k * sample_ticks
        # run the PWM and plant up to the sample instant
        while True:
            cands = [ts] + next_start + [t for t in next_off if t is not None]
            nxt = min(cands)
            if nxt > now:
                plant.advance((nxt - now) * tick, pins)
                calls += 1
                now = nxt
            changed = False
            for a in range(2):
                if next_off[a] == now:
                    next_off[a] = None
                    pins[a] = _pins(active[a], False, cfg.drive)
                    changed = True
                if next_start[a] == now:
                    active[a] = pending[a]
                    on_ticks = abs(active[a]) * period_ticks[a] // full
                    pins[a] = _pins(active[a], on_ticks > 0, cfg.drive)
                    next_off[a] = now + on_ticks if 0 < on_ticks < period_ticks[a] else None
                    next_start[a] = now + period_ticks[a]
                    changed = True
            if now == ts and not changed:
                break
            if now == ts and min(next_start + [t for t in next_off if t is not None]) > now:
                break
        # sample: the firmware reads the decoder counts
        for a in range(2):
            x = plant.count(a) / counts_per_rad
            if k > 0:
                v[a] = cfg.vel_filter * (x - x_prev[a]) / cfg.sample_s + (1 - cfg.vel_filter) * v[a]
            x_prev[a] = x
            e = cfg.setpoint_rad - x
            g = cfg.gains[a]
            e_sign = (e > 0) - (e < 0)
            if not (cfg.anti_windup and sat_sign[a] != 0 and sat_sign[a] == e_sign):
                integ[a] += e * cfg.sample_s
            if cfg.anti_windup and g.ki > 0:
                lim = tau_max[a] / g.ki
                integ[a] = max(-lim, min(lim, integ[a]))
            tau = g.kp * e - g.kd * v[a] + g.ki * integ[a]
            sat_sign[a] = 1 if tau > tau_max[a] else (-1 if tau < -tau_max[a] else 0)
            pending[a] = duty_from_torque(tau, tau_max[a], cfg)
            res.t[k] = k * cfg.sample_s
            res.x_meas[k, a] = x
            res.x_true[k, a] = plant.screw_angle(a)
            res.table_mm[k, a] = plant.table_mm(a)
            res.v_est[k, a] = v[a]
            res.duty[k, a] = active[a] / full
            res.current[k, a] = plant.current(a)
        if progress and k % max(1, n_samples // 20) == 0:
            print(f"  t = {k * cfg.sample_s:5.1f} s  x = {res.x_meas[k, 0]:.3f} / "
                  f"{res.x_meas[k, 1]:.3f} rad", flush=True)
    res.wall_s = time.monotonic() - t0
    res.calls = calls
    return res


def step_metrics(t: np.ndarray, x: np.ndarray, setpoint: float) -> dict[str, float]:
    """Rise time (10-90 %), overshoot, final error and RMSE of eq (26)."""
    e = setpoint - x
    def first(th: float) -> float:
        idx = np.nonzero(x >= th * setpoint)[0]
        return float(t[idx[0]]) if idx.size else math.nan
    return {"rise_s": first(0.9) - first(0.1),
            "overshoot_pct": float(max(0.0, (x.max() - setpoint) / setpoint * 100)),
            "final_error_rad": float(e[-1]),
            "rmse_rad": float(math.sqrt(np.trapezoid(e**2, t) / (t[-1] - t[0])))}


def run_all(names: Sequence[str] = ("P", "PD", "PID"), **kw: object) -> dict[str, LoopResult]:
    return {n: run_loop(LoopConfig(gains=TABLE1[n], **kw)) for n in names}  # type: ignore[arg-type]
