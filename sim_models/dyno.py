# SPDX-License-Identifier: MIT
"""Dynamometer bench of the characterisation method (paper sec. II.A-B, VI.A).

The motor's output shaft carries a wheel of radius r; a rope from the wheel
to a force meter holds it still, so the meter reads F = tau / (r sin theta)
(paper: tau = r F sin theta).  With the rotor held, the back-EMF is zero and
the armature is a plain R-L load on the BTS7960 bridge driven by a PWM pin
waveform of frequency f and duty d.  The meter and an ammeter average over a
settled window, which is what :meth:`DynamometerBench.measure` returns.

Drive modes (``drive``):

- ``"brake"`` (slow decay, the usual IBT-2 drive): R_EN = L_EN = 1, RPWM
  carries the PWM, LPWM = 0.  Off-phase: both low sides on, the current
  free-wheels through the motor.
- ``"coast"`` (fast decay): RPWM = 1, LPWM = 0 and both enables carry the
  PWM.  Off-phase: both sides off, the current returns to the supply through
  the body diodes against V_s + 2 V_f and, if it reaches zero, stays there.

What makes torque depend on frequency here, and what does not:

- Brake mode: the mean current of a periodic R-L response to a rectangular
  voltage is exactly the mean voltage over R, whatever the frequency.  The
  only frequency dependence is the bridge's pulse shortening (0.7 us per
  pulse, data sheet typ.), i.e. a duty loss of 0.7 us x f: 0.03 % at 450 Hz.
- Coast mode: the off-phase drives the current to zero within a fraction of
  L/R (0.2 ms), and the on-phase starts from zero each period, so the mean
  current is below d V / R by about tau_e f (V/R) minus the decay tail: the
  torque at 50 % duty falls with frequency (about 10 % at 450 Hz).
- Not modelled: rotor motion under the torque ripple (the rope holds the
  output shaft), brush contact drop, iron losses, the meter's compliance.

Consequently the simulated motors do NOT reproduce the paper's "optimal
frequencies" (torque at 50 % = tau_max / 2 at 450 Hz and 200 Hz): in brake
mode every frequency gives tau_max / 2, in coast mode the torque at 50 % is
below tau_max / 2 at every frequency and approaches it only as f -> 0.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from sim_models.bridge import Pins, armature_voltages, path_resistance
from sim_models.params import AxisParams, BridgeParams


@dataclass(frozen=True)
class DynoConfig:
    wheel_radius_m: float = 0.02     # not given in the paper (Fig 1, 12)
    rope_angle_deg: float = 90.0     # theta of tau = r F sin(theta)
    drive: str = "brake"             # "brake" (slow decay) or "coast" (fast decay)
    settle_periods: int = 10         # plus at least 20 L/R time constants
    average_periods: int = 10


@dataclass(frozen=True)
class Measurement:
    force_N: float          # force meter reading (mean)
    torque_N_m: float       # output-shaft torque, r F sin(theta)
    current_A: float        # mean armature current (the supply ammeter reads mean supply current)
    current_rms_A: float
    is_pin_A: float         # mean current out of the active IS pin


def _pins(drive: str, on: bool, direction: int) -> Pins:
    if drive == "brake":
        pwm = 1 if on else 0
        return Pins(pwm, 0, 1, 1) if direction > 0 else Pins(0, pwm, 1, 1)
    if drive == "coast":
        en = 1 if on else 0
        return Pins(1, 0, en, en) if direction > 0 else Pins(0, 1, en, en)
    raise ValueError(f"unknown drive mode {drive!r}")


class DynamometerBench:
    """Stalled-rotor bench: PWM pin waveform in, force/torque/current out."""

    def __init__(self, axis: AxisParams, bridge: BridgeParams,
                 config: DynoConfig | None = None) -> None:
        self.axis = axis
        self.bridge = bridge
        self.config = config or DynoConfig()
        self.r_tot = axis.resistance_ohm + path_resistance(bridge)
        self.tau_e = axis.inductance_H / self.r_tot

    def _segment(self, i0: float, dur: float, pins: Pins) -> tuple[float, float, float, float]:
        """R-L response with zero back-EMF over ``dur``: returns
        (i_end, integral of i, integral of i^2, integral of high-side i)."""
        e_pos, e_neg = armature_voltages(pins, self.bridge)
        r, tau = self.r_tot, self.tau_e
        t_left, i = dur, i0
        q = q2 = qhs = 0.0
        hs = (pins.r_en and pins.rpwm) or (pins.l_en and pins.lpwm)
        while t_left > 0:
            if i == 0.0:
                if e_pos > 0:
                    e = e_pos
                elif e_neg < 0:
                    e = e_neg
                else:
                    break            # no diode conducts: i stays 0
            else:
                e = e_pos if i > 0 else e_neg
            inf = e / r
            t = t_left
            # a floating side: the current stops at zero instead of reversing
            if e_pos != e_neg and inf * i < 0:
                tz = tau * math.log((i - inf) / (-inf))
                if tz < t:
                    t = tz
            ex = math.exp(-t / tau)
            a = i - inf
            seg = inf * t + a * tau * (1 - ex)
            seg2 = (inf * inf * t + 2 * inf * a * tau * (1 - ex)
                    + a * a * tau / 2 * (1 - ex * ex))
            q += seg
            q2 += seg2
            if hs:
                qhs += seg
            t_left -= t
            # stopped at the zero crossing, or ran to the end of the segment
            i = 0.0 if t_left > 0 else inf + a * ex
        return i, q, q2, qhs

    def measure(self, freq_hz: float, duty: float, direction: int = 1,
                drive: str | None = None) -> Measurement:
        """Mean force, torque and current over ``average_periods`` PWM
        periods after the current has settled.  Cost: about 10 us per period."""
        cfg = self.config
        drive = drive or cfg.drive
        period = 1.0 / freq_hz
        b = self.bridge
        on_t = duty * period + b.turn_off_delay_s - b.turn_on_delay_s
        on_t = min(max(on_t, 0.0), period) if 0 < duty < 1 else duty * period
        pins_on, pins_off = _pins(drive, True, direction), _pins(drive, False, direction)
        settle = max(cfg.settle_periods, math.ceil(20 * self.tau_e / period))
        i = 0.0
        q = q2 = qhs = 0.0
        for k in range(settle + cfg.average_periods):
            i, a1, b1, c1 = self._segment(i, on_t, pins_on)
            i, a2, b2, c2 = self._segment(i, period - on_t, pins_off)
            if k >= settle:
                q += a1 + a2
                q2 += b1 + b2
                qhs += c1 + c2
        t_avg = cfg.average_periods * period
        i_mean = q / t_avg
        torque = self.axis.km_N_m_per_A * i_mean   # k_m: output-shaft torque per amp
        force = torque / (cfg.wheel_radius_m * math.sin(math.radians(cfg.rope_angle_deg)))
        return Measurement(force_N=force, torque_N_m=torque, current_A=i_mean,
                           current_rms_A=math.sqrt(max(q2 / t_avg, 0.0)),
                           is_pin_A=abs(qhs / t_avg) / b.k_ilis)

    def tau_max(self) -> float:
        """Step 2 of the method: the stall torque at nominal voltage (duty 100 %)."""
        return self.measure(1000.0, 1.0).torque_N_m
