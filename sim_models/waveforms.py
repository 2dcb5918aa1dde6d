# SPDX-License-Identifier: MIT
"""Input waveforms for the plant's own tests and benchmarks: a carrier of
any frequency with any duty fraction, on the FPGA clock grid, and the fast
stepper run through one.  (What the board's PWM block makes is modelled by
torqueloop.oracles.pwm_schedule, which the simulations of the board use.)"""

from __future__ import annotations

from typing import Callable

import numpy as np

from sim_models.bridge import Pins
from sim_models.params import AxisParams, PlantParams
from sim_models.stepper import FastAxis

CLK_TICK = 20e-9   # 50 MHz: pin edges fall on this grid, as in the co-simulation


def pwm_schedule(t_end: float, freq_hz: float, duty_of: Callable[[int], float],
                 on_pins_of: Callable[[int], Pins], off_pins_of: Callable[[int], Pins]
                 ) -> list[tuple[float, Pins]]:
    """(t_start, pins) list of a PWM waveform on the FPGA clock grid; the
    duty, on-pins and off-pins may vary with the period index k."""
    per = round(1.0 / freq_hz / CLK_TICK)
    out: list[tuple[float, Pins]] = []
    k = 0
    while k * per * CLK_TICK < t_end:
        on = round(duty_of(k) * per)
        out.append((k * per * CLK_TICK, on_pins_of(k)))
        if 0 < on < per and (k * per + on) * CLK_TICK < t_end:
            out.append(((k * per + on) * CLK_TICK, off_pins_of(k)))
        k += 1
    return out


def run_fast(a: AxisParams, plant: PlantParams, schedule: list[tuple[float, Pins]],
             t_end: float, index: int = 0, **kw: float) -> tuple[np.ndarray, FastAxis]:
    """States of the fast stepper at the schedule boundaries and t_end."""
    fa = FastAxis(a, plant, index, **kw)
    out: list = []
    xs = [fa.x.copy()]
    bounds = [s[0] for s in schedule[1:]] + [t_end]
    for (ts, p), te in zip(schedule, bounds):
        fa.set_pins(p)
        fa.advance(te - ts, out)
        xs.append(fa.x.copy())
    return np.array(xs), fa
