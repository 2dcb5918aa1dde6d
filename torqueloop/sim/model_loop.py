# SPDX-License-Identifier: MIT
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
tau = K_p e + K_d (-v) + K_i sum(e T_s), the 10-bit command of eq. (23)-(25)
with saturation eq (19) (torqueloop.spec.pwm.command_for), and the board's
PWM block (torqueloop.oracles.pwm_schedule: the divisor of eq. 4 for each
carrier, dead-zone compensation eq (1) with PW0, double buffering), the
one event-level model of the PWM that every simulation without the RTL uses.  The integral has the
firmware's anti-windup (held while the output saturates in the error's
direction, its term kept within full scale; ``anti_windup=False`` for the
plain eq. (22) sum), so that RTL-in-the-loop and this loop run one law.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np

from sim_models.params import PlantParams, load_params
from sim_models.stepper import TwoAxisPlant
from torqueloop.oracles.pwm_schedule import PwmChannel, PwmSetting, run_until
from torqueloop.spec.bridge import BRAKE, COAST
from torqueloop.spec.pwm import command_for, divider_for, duty_ticks, full_scale
from torqueloop.spec.system import SYSTEM, Gains

#: Table 1, "Given value" column: (axis x, axis z) - torqueloop/spec/system.toml
TABLE1: dict[str, tuple[Gains, ...]] = SYSTEM.table1


@dataclass(frozen=True)
class LoopConfig:
    setpoint_rad: float = SYSTEM.step_rad     # one screw turn = 4 mm (sec. VI.B)
    t_end_s: float = SYSTEM.t_end_s           # T of eq (26)
    sample_s: float = SYSTEM.period_us * 1e-6  # 2.5e-2 s (sec. VI.B)
    vel_filter: float = SYSTEM.vel_filter     # weight of the new Euler difference
    pwm_bits: int = SYSTEM.pwm_bits           # gamma = 2^10 (eq 2)
    clk_hz: int = SYSTEM.clk_hz               # PWM edges fall on the FPGA clock
    pw0: int = 0                              # dead zone PW0 of eq (1), ticks of 2^bits - 1
    drive: str = "brake"                      # off-phase: "brake" (slow decay) or "coast"
    pwm_hz: tuple[float, ...] = SYSTEM.pwm_hz
    gains: tuple[Gains, ...] = field(default_factory=lambda: TABLE1["P"])
    # Integrator held while the output is saturated in the direction the error
    # pushes, and its term kept within full scale: what the firmware does
    # (docs/firmware.md).  False gives the plain eq. (22) integral.
    anti_windup: bool = True

    def __post_init__(self) -> None:
        if self.drive not in ("brake", "coast"):
            raise ValueError(f"drive must be 'brake' or 'coast', not {self.drive!r}")


@dataclass
class LoopResult:
    t: np.ndarray              # sample times (s)
    x_meas: np.ndarray         # (n, 2) screw angle from the encoder (rad)
    x_true: np.ndarray         # (n, 2) screw angle of the model (rad)
    table_mm: np.ndarray       # (n, 2)
    v_est: np.ndarray          # (n, 2) filtered speed estimate (rad/s)
    duty: np.ndarray           # (n, 2) signed duty applied (fraction of the period)
    current: np.ndarray        # (n, 2) armature current at the sample (A)
    cmd: np.ndarray            # (n, 2) the command computed at the sample (applied from the next period)
    wall_s: float = 0.0
    calls: int = 0


class Law:
    """One axis's control law as the firmware runs it (and as eq. 20-22 read
    with Table 1): the paper's filtered Euler speed (sec. VI.B), the torque
    K_p e - K_d v + K_i sum(e T_s), the integral held while the output is
    saturated in the error's direction and its term kept within full scale
    (``anti_windup``; off: the plain eq. 22 sum), and the torque as a
    fraction of tau_max (eq. 23-25; the caller saturates and quantises)."""

    def __init__(self, gains: Gains, tau_max_N_m: float, sample_s: float, vel_filter: float,
                 anti_windup: bool = True) -> None:
        self.g, self.tau_max, self.ts, self.a, self.aw = gains, tau_max_N_m, sample_s, vel_filter, anti_windup
        self.x_prev = 0.0
        self.v = 0.0
        self.integ = 0.0
        self.sat_sign = 0
        self.first = True

    def step(self, x: float, target: float) -> float:
        """Take the position sample ``x``; return tau / tau_max (unsaturated)."""
        if not self.first:
            self.v = self.a * (x - self.x_prev) / self.ts + (1 - self.a) * self.v
        self.first = False
        self.x_prev = x
        e = target - x
        e_sign = (e > 0) - (e < 0)
        if not (self.aw and self.sat_sign != 0 and self.sat_sign == e_sign):
            self.integ += e * self.ts
        if self.aw and self.g.ki > 0:
            lim = self.tau_max / self.g.ki
            self.integ = max(-lim, min(lim, self.integ))
        tau = self.g.kp * e - self.g.kd * self.v + self.g.ki * self.integ
        self.sat_sign = 1 if tau > self.tau_max else (-1 if tau < -self.tau_max else 0)
        return tau / self.tau_max


def run_loop(cfg: LoopConfig, params: PlantParams | None = None,
             plant: TwoAxisPlant | None = None, progress: bool = False) -> LoopResult:
    """Step both axes to ``setpoint_rad`` from rest and record every sample."""
    params = params or load_params()
    plant = plant or TwoAxisPlant(params, seed=0)
    full = full_scale(cfg.pwm_bits)
    off = BRAKE if cfg.drive == "brake" else COAST
    divs = [divider_for(f, cfg.clk_hz, cfg.pwm_bits) for f in cfg.pwm_hz]
    channels = [PwmChannel(PwmSetting(div=d, pw0=cfg.pw0, pwmax=full, safe=off), off_phase=off,
                           pwm_bits=cfg.pwm_bits) for d in divs]
    counts_per_rad = params.encoder.counts_per_motor_rev * params.axes[0].gear_ratio / (2 * math.pi)
    laws = [Law(cfg.gains[a], params.axes[a].tau_max_paper_N_m, cfg.sample_s, cfg.vel_filter, cfg.anti_windup)
            for a in range(2)]
    n_samples = int(round(cfg.t_end_s / cfg.sample_s)) + 1
    sample_ticks = round(cfg.sample_s * cfg.clk_hz)
    z = lambda: np.zeros((n_samples, 2))  # noqa: E731
    res = LoopResult(np.zeros(n_samples), z(), z(), z(), z(), z(), z(), z())
    t0 = time.monotonic()
    calls = 0
    for k in range(n_samples):
        # run the PWM and plant up to the sample instant (events at it included)
        calls += run_until(plant, channels, (k - 1) * sample_ticks if k else 0, k * sample_ticks, cfg.clk_hz)
        # sample: the firmware reads the decoder counts
        for a in range(2):
            x = plant.count(a) / counts_per_rad
            cmd = command_for(laws[a].step(x, cfg.setpoint_rad), cfg.pwm_bits)
            channels[a].load(PwmSetting(cmd=cmd, div=divs[a], pw0=cfg.pw0, pwmax=full, safe=off))
            act = channels[a].active
            res.t[k] = k * cfg.sample_s
            res.x_meas[k, a] = x
            res.x_true[k, a] = plant.screw_angle(a)
            res.table_mm[k, a] = plant.table_mm(a)
            res.v_est[k, a] = laws[a].v
            res.duty[k, a] = math.copysign(duty_ticks(act.cmd, act.pw0, act.pwmax, cfg.pwm_bits) / full, act.cmd)
            res.current[k, a] = plant.current(a)
            res.cmd[k, a] = cmd
        if progress and k % max(1, n_samples // 20) == 0:
            print(f"  t = {k * cfg.sample_s:5.1f} s  x = {res.x_meas[k, 0]:.3f} / "
                  f"{res.x_meas[k, 1]:.3f} rad", flush=True)
    res.wall_s = time.monotonic() - t0
    res.calls = calls
    return res


def run_averaged(cfg: LoopConfig, params: PlantParams | None = None,
                 plant: TwoAxisPlant | None = None) -> LoopResult:
    """The paper's simulation (sec. VI.B): eq. (7) and (17) driven by the
    armature voltage u V averaged over the PWM period (an ideal source held
    over each control sample: no PWM ripple), the position read without
    encoder quantisation (the motor angle over G, where the encoder sits),
    u = tau / tau_max saturated at +-1 (eq. 19) and not quantised; the law
    of :class:`Law`.  ``cfg.pwm_hz``, ``pw0`` and ``drive`` do not apply."""
    params = params or load_params()
    plant = plant or TwoAxisPlant(params, seed=0)
    laws = [Law(cfg.gains[a], params.axes[a].tau_max_paper_N_m, cfg.sample_s, cfg.vel_filter, cfg.anti_windup)
            for a in range(2)]
    n_samples = int(round(cfg.t_end_s / cfg.sample_s)) + 1
    z = lambda: np.zeros((n_samples, 2))  # noqa: E731
    res = LoopResult(np.zeros(n_samples), z(), z(), z(), z(), z(), z(), z())
    supply = params.bridge.supply_V
    volts = [0.0, 0.0]
    t0 = time.monotonic()
    for k in range(n_samples):
        if k:
            plant.advance_volts(cfg.sample_s, volts)
        for a in range(2):
            x = plant.motor_angle(a) / params.axes[a].gear_ratio
            u = max(-1.0, min(1.0, laws[a].step(x, cfg.setpoint_rad)))
            volts[a] = u * supply
            res.t[k] = k * cfg.sample_s
            res.x_meas[k, a] = x
            res.x_true[k, a] = plant.screw_angle(a)
            res.table_mm[k, a] = plant.table_mm(a)
            res.v_est[k, a] = laws[a].v
            res.duty[k, a] = u
            res.current[k, a] = plant.current(a)
            res.cmd[k, a] = u * full_scale(cfg.pwm_bits)
    res.wall_s = time.monotonic() - t0
    res.calls = n_samples
    return res


def run_all(names: tuple[str, ...] = ("P", "PD", "PID"), **kw: object) -> dict[str, LoopResult]:
    return {n: run_loop(LoopConfig(gains=TABLE1[n], **kw)) for n in names}  # type: ignore[arg-type]
