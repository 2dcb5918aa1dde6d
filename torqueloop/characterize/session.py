# SPDX-License-Identifier: MIT
"""A lab's session of the method (steps 2-7), whatever makes the readings:
record the frequency sweep, ask the method where to record a duty sweep,
record it, repeat until the method passes, fails, or ``max_duty_sweeps``
were recorded.  Every sweep is written to ``out_dir`` as the lab's CSV files
and read back, so the method sees what a lab would hand it.  The simulated
bench (:mod:`.simbench`) and the board with a force gauge (:mod:`.board`)
both run it."""

from __future__ import annotations

from pathlib import Path
from typing import Callable

from .data import Sweep, read_sweep, write_sweep
from .method import MotorResult, Thresholds, characterize_motor

#: step 6's duty sweep, 1-99 % (the commands a session asks for)
DUTY_PCTS: tuple[float, ...] = (1.0, *(float(d) for d in range(3, 100, 3)))


def run_session(record_frequency: Callable[[], Sweep], record_duty: Callable[[float], Sweep], out_dir: Path,
                tag: str, th: Thresholds = Thresholds(), max_duty_sweeps: int = 4) -> MotorResult:
    out_dir.mkdir(parents=True, exist_ok=True)
    fpath = out_dir / "freq_sweep.csv"
    write_sweep(fpath, record_frequency(), comment=tag)
    fs = read_sweep(fpath)
    duty: list[Sweep] = []
    while True:
        r = characterize_motor(fs, duty, th)
        if r.status != "need_duty_sweep" or len(duty) >= max_duty_sweeps:
            return r
        assert r.next_freq_hz is not None
        ds = record_duty(r.next_freq_hz)
        dpath = out_dir / f"duty_sweep_{ds.freq_hz:.0f}hz.csv"
        write_sweep(dpath, ds, comment=tag)
        duty.append(read_sweep(dpath))
