"""Shared helpers of the plant tests (not collected: no test_ prefix)."""

from __future__ import annotations

import numpy as np

from sim_models.bridge import Pins
from sim_models.params import AxisParams, PlantParams
from sim_models.stepper import FastAxis

CLK_TICK = 20e-9   # schedules on the 50 MHz FPGA clock, as the co-simulation will be


def pwm_schedule(t_end: float, freq_hz: float, duty_of, on_pins_of, off_pins_of
                 ) -> list[tuple[float, Pins]]:
    """(t_start, pins) list of a PWM waveform on the FPGA clock grid; the
    duty, on-pins and off-pins may vary per period k."""
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
    """States of the fast stepper at the schedule boundaries and t_end
    (the same instants the reference returns)."""
    fa = FastAxis(a, plant, index, **kw)
    out: list = []
    xs = [fa.x.copy()]
    bounds = [s[0] for s in schedule[1:]] + [t_end]
    for (ts, p), te in zip(schedule, bounds):
        fa.set_pins(p)
        fa.advance(te - ts, out)
        xs.append(fa.x.copy())
    return np.array(xs), fa
