# SPDX-License-Identifier: MIT
"""The simulated characterisation bench: the lab's sweeps with no hardware.

Two pin sources feed the same measurement:

* ``"rtl"`` - the project's own frequency divider and PWM block
  (rtl/motion/freq_div, rtl/motion/pwm_torque, wrapped in
  char_bench_top.v beside this module, captured by :mod:`.rtl_capture`) run in a cocotb simulation; the IBT-2 pin
  waveform of one whole period per setting is captured;
* ``"model"`` - the same waveform computed from the cores' documented
  behaviour (a period of Count_max x (2^N - 1) clocks, RPWM high for
  duty x Count_max clocks), for quick runs; the RTL source checks it.

The RTL part lives here; the dynamometer (pin waveform in, force and
current out) is the plant's rope bench (sim_models.dyno.RopeDynamometer) on
a named plant variant (sim_models.variants), read through its instruments
with seeded noise.  Pin waveforms are cached per setting, and the bench
caches the physics of each setting, so a session repeated with other seeds
(other instrument noise) costs only the settings it has not seen.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable, Literal, Sequence

import numpy as np

from sim_models.variants import PlantSpec
from torqueloop.flow.manifest import REPO_ROOT, core

from torqueloop.spec.charconfig import Config
from torqueloop.spec.pwm import divider_for, full_scale as pwm_full_scale

from .config import CLK_HZ, PWM_BITS
from .data import BenchConstants, Sweep
from .method import MotionDeadZone, MotorResult, Thresholds, motion_dead_zone
from .session import DUTY_PCTS, run_session

CHAR_BENCH_TOP = Path(__file__).resolve().with_name("char_bench_top.v")
CLK_PS = 20_000  # CLOCK_50
PinSource = Literal["rtl", "model"]
Drive = Literal["brake", "coast"]


@dataclass(frozen=True)
class PinWaveform:
    """IBT-2 pins over one PWM period: ``segments`` are (start time s, pins)
    with pins = (rpwm, lpwm, r_en, l_en), each held until the next start;
    the waveform repeats with ``period_s``."""

    count_max: int
    duty_counts: int
    period_s: float
    segments: tuple[tuple[float, tuple[int, int, int, int]], ...]

    @property
    def freq_hz(self) -> float:
        return 1.0 / self.period_s

    @property
    def high_s(self) -> float:
        """Time RPWM is high in the period."""
        t = 0.0
        for k, (start, pins) in enumerate(self.segments):
            end = self.segments[k + 1][0] if k + 1 < len(self.segments) else self.period_s
            if pins[0]:
                t += end - start
        return t


def model_waveform(count_max: int, duty_counts: int, clk_hz: int = CLK_HZ, pwm_bits: int = PWM_BITS,
                   drive: Drive = "brake") -> PinWaveform:
    """What freq_div + pwm_torque make for a forward duty (docs/pwm_torque.md):
    a period of M ticks of Count_max clocks, on for ``duty`` ticks.  ``brake``
    is what pwm_torque drives in IBT-2 mode (PWM on RPWM, enables high: the
    off-phase brakes on the low sides); ``coast`` (RPWM high, PWM on both
    enables: the off-phase floats the bridge) is the other way to wire an
    IBT-2, for comparison - the RTL does not make it."""
    m = pwm_full_scale(pwm_bits)
    tick_s = max(1, count_max) / clk_hz
    period = m * tick_s
    on = (1, 0, 1, 1)
    off = (0, 0, 1, 1) if drive == "brake" else (1, 0, 0, 0)
    if duty_counts <= 0:
        segs: tuple = ((0.0, off),)
    elif duty_counts >= m:
        segs = ((0.0, on),)
    else:
        segs = ((0.0, on), (duty_counts * tick_s, off))
    return PinWaveform(count_max, duty_counts, period, segs)


def drive_and_duty(w: PinWaveform) -> tuple[Drive, float]:
    """Read a forward IBT-2 pin waveform: which off-phase it uses and the
    fraction of the period the bridge drives the motor.  Anything else (a
    reverse pulse, both sides driven, a glitch) is refused: the dynamometer
    model takes a rectangular forward drive."""
    on, brake_off, coast_off = (1, 0, 1, 1), (0, 0, 1, 1), (1, 0, 0, 0)
    kinds = {p for _, p in w.segments}
    if not kinds <= {on, brake_off, coast_off} or {brake_off, coast_off} <= kinds:
        raise ValueError(f"pin waveform is not a forward IBT-2 PWM: pin states {sorted(kinds)}")
    t_on = 0.0
    for k, (start, p) in enumerate(w.segments):
        end = w.segments[k + 1][0] if k + 1 < len(w.segments) else w.period_s
        if p == on:
            t_on += end - start
    return ("coast" if coast_off in kinds else "brake"), t_on / w.period_s


def _rtl_waveforms(settings: Sequence[dict], sim: str, work: Path) -> list[dict]:
    from torqueloop.flow.simrun import run

    work.mkdir(parents=True, exist_ok=True)
    job, result = work / "job.json", work / "result.json"
    job.write_text(json.dumps(list(settings)))
    result.unlink(missing_ok=True)
    run(
        "pwm_torque", sim, "torqueloop.characterize.rtl_capture",
        toplevel="char_bench_top",
        extra_verilog=[*core("freq_div").verilog, CHAR_BENCH_TOP],
        testcase="capture",
        extra_env={"CHAR_BENCH_JOB": str(job.resolve()), "CHAR_BENCH_RESULT": str(result.resolve())},
    )
    return json.loads(result.read_text())


def rtl_waveforms(settings: Sequence[tuple[int, int]], sim: str = "verilator", work: Path | None = None,
                  pw0: int = 0, pw_max: int | None = None) -> list[PinWaveform]:
    """Pin waveforms of the RTL for (count_max, cmd) settings.  With the
    default pw0 = 0 and pw_max = M the command is the duty in counts."""
    m = pwm_full_scale(PWM_BITS)
    pm = m if pw_max is None else pw_max
    work = work or (REPO_ROOT / "build" / "char_bench" / sim)
    raw = _rtl_waveforms([{"count_max": n, "cmd": c, "pw0": pw0, "pw_max": pm} for n, c in settings], sim, work)
    out = []
    for r in raw:
        segs = tuple((s[0] * 1e-12, (s[1], s[2], s[3], s[4])) for s in r["segments_ps"])
        w = PinWaveform(r["count_max"], 0, r["period_ps"] * 1e-12, segs)
        # duty in counts as the pins show it: high time over one tick (Count_max clocks)
        duty = round(w.high_s / (r["count_max"] * CLK_PS * 1e-12))
        out.append(PinWaveform(r["count_max"], duty, w.period_s, segs))
    return out


def check_config_on_pins(cfg: Config, axis: str, sim: str = "icarus", work: Path | None = None) -> dict[str, float]:
    """Program an axis's Count_max, PW0 and PW_F from a configuration into
    the RTL and measure its pins: carrier frequency, and the duty counts of
    the smallest (cmd 1) and the full (cmd M) command."""
    a = cfg.axes[axis]
    m = pwm_full_scale(cfg.pwm_bits)
    wf = rtl_waveforms([(a.count_max, 1), (a.count_max, m)], sim=sim, work=work,
                       pw0=a.pw0_counts, pw_max=a.pw_max_counts)
    return {
        "freq_hz": wf[0].freq_hz,
        "freq_hz_full": wf[1].freq_hz,
        "duty_counts_cmd1": wf[0].duty_counts,
        "duty_counts_full": wf[1].duty_counts,
    }


# ---------------------------------------------------------------- the sweeps


@dataclass(frozen=True)
class Reading:
    """What the lab writes down at one setting."""

    force_n: float
    current_a: float
    current_std_a: float | None = None
    settle_s: float | None = None
    """how long the setting was held before the reading (the bench's settle rule)"""


def log_frequencies(lo: float = 50.0, hi: float = 24_500.0, n: int = 25) -> tuple[float, ...]:
    """The sweep's frequencies: ``n`` log-spaced from ``lo`` to ``hi`` (4
    significant digits), less those whose nearest board carrier (eq. 4) an
    earlier one already has: above a few kHz the divider reaches only a few
    carriers (Count_max 3, 2: 16.3, 24.4 kHz).  The top, 24.4 kHz, is the
    highest carrier within the IBT-2's 25 kHz rating."""
    out: list[float] = []
    seen: set[int] = set()
    for f in np.geomspace(lo, hi, n):
        d = divider_for(float(f), CLK_HZ, PWM_BITS)
        if d not in seen:
            seen.add(d)
            out.append(float(f"{f:.4g}"))
    return tuple(out)


@dataclass(frozen=True)
class SweepPlan:
    """The sweeps.  The paper swept 50-500 Hz at 12 V; this bench sweeps
    50 Hz - 20 kHz log-spaced (the IBT-2's rating is 25 kHz), to see where a
    frequency dependence lives; duty 1-99 %."""

    freqs_hz: tuple[float, ...] = field(default_factory=log_frequencies)
    duty_pcts: tuple[float, ...] = DUTY_PCTS
    wheel_radius_m: float = 0.025
    theta_deg: float = 90.0
    supply_v: float = 12.0


Measure = Callable[[PinWaveform], Reading]


class Waveforms:
    """Pin waveforms per (count_max, duty) setting, from the RTL or the
    model, each computed once (a session and its seeds ask for the same
    settings again)."""

    def __init__(self, source: PinSource = "model", sim: str = "verilator", work: Path | None = None,
                 drive: Drive = "brake") -> None:
        if source == "rtl" and drive != "brake":
            raise ValueError("the RTL drives the IBT-2 with a braking off-phase only (pwm_torque dir_mode 0)")
        self.source, self.sim, self.drive = source, sim, drive
        self.work = work or (REPO_ROOT / "build" / "char_bench" / sim)
        self._cache: dict[tuple[int, int], PinWaveform] = {}
        self.rtl_runs = 0

    def get(self, settings: Sequence[tuple[int, int]]) -> list[PinWaveform]:
        todo = sorted({s for s in settings if s not in self._cache})
        if todo:
            if self.source == "rtl":
                got = rtl_waveforms(todo, sim=self.sim, work=self.work / f"run{self.rtl_runs}")
                self.rtl_runs += 1
            else:
                got = [model_waveform(n, c, drive=self.drive) for n, c in todo]
            self._cache.update(zip(todo, got))
        return [self._cache[s] for s in settings]


def _std(rd: Sequence[Reading]) -> np.ndarray | None:
    if any(r.current_std_a is None for r in rd):
        return None
    return np.array([r.current_std_a for r in rd])


def _progress(msg: str) -> None:
    print(f"[simbench] {msg}", flush=True)


def record_frequency_sweep(measure: Measure, plan: SweepPlan, motor: str, wf: Waveforms) -> Sweep:
    """Steps 2-4 on the simulated bench: the stall reading (duty M, constantly
    on) and the 50 % sweep.  50 % of the 1023-count period is not a whole
    count: 512 counts (50.05 %) is used and written as the sweep's duty."""
    m = pwm_full_scale(PWM_BITS)
    half = (m + 1) // 2
    counts = [divider_for(f, CLK_HZ, PWM_BITS) for f in plan.freqs_hz]
    settings = [(counts[0], m)] + [(n, half) for n in counts]
    wfs = wf.get(settings)
    rd = [measure(w) for w in wfs]
    bench = BenchConstants(plan.wheel_radius_m, plan.theta_deg, plan.supply_v)
    k = float(bench.torque_nm(1.0))
    return Sweep(
        "frequency", motor, bench,
        x=np.array([w.freq_hz for w in wfs[1:]]),
        torque_nm=np.array([r.force_n * k for r in rd[1:]]),
        current_a=np.array([r.current_a for r in rd[1:]]),
        current_std_a=_std(rd[1:]),
        duty_pct=100.0 * half / m,
        stall_torque_nm=rd[0].force_n * k, stall_current_a=rd[0].current_a,
        force_given=True,
    )


def duty_settings(plan: SweepPlan, freq_hz: float) -> list[tuple[int, int]]:
    """The (Count_max, duty counts) settings of a duty sweep at the board
    frequency nearest ``freq_hz``."""
    m = pwm_full_scale(PWM_BITS)
    n = divider_for(freq_hz, CLK_HZ, PWM_BITS)
    return [(n, d) for d in sorted({max(1, min(m - 1, int(round(d / 100.0 * m)))) for d in plan.duty_pcts})]


def record_duty_sweep(measure: Measure, plan: SweepPlan, motor: str, freq_hz: float, wf: Waveforms) -> Sweep:
    """Step 6 on the simulated bench at the board frequency nearest ``freq_hz``."""
    m = pwm_full_scale(PWM_BITS)
    wfs = wf.get(duty_settings(plan, freq_hz))
    rd = [measure(w) for w in wfs]
    bench = BenchConstants(plan.wheel_radius_m, plan.theta_deg, plan.supply_v)
    k = float(bench.torque_nm(1.0))
    return Sweep(
        "duty", motor, bench,
        x=np.array([100.0 * w.duty_counts / m for w in wfs]),
        torque_nm=np.array([r.force_n * k for r in rd]),
        current_a=np.array([r.current_a for r in rd]),
        current_std_a=_std(rd),
        freq_hz=wfs[0].freq_hz,
        force_given=True,
    )


def run_bench(measure: Measure, out_dir: Path, motor: str, plan: SweepPlan = SweepPlan(),
              th: Thresholds = Thresholds(), wf: Waveforms | None = None, max_duty_sweeps: int = 4,
              tag: str = "") -> MotorResult:
    """A lab's session on the simulated bench (:func:`.session.run_session`); every
    sweep is written to ``out_dir`` as the lab's CSV files."""
    wf = wf or Waveforms()
    tag = tag or f"simulated bench: {wf.source} pins, {wf.drive} off-phase, motor {motor}"
    return run_session(lambda: record_frequency_sweep(measure, plan, motor, wf),
                       lambda f: record_duty_sweep(measure, plan, motor, f, wf), out_dir, tag, th, max_duty_sweeps)


# ---------------------------------------------------------------- the plant's rope dynamometer


class LabBench:
    """The rope dynamometer (sim_models.dyno) for each axis of a plant
    variant, its physics cached across sessions; ``measure(axis, seed)``
    gives a :data:`Measure` whose instrument noise comes from ``seed``."""

    def __init__(self, plant: PlantSpec = PlantSpec("lab"), config: "object | None" = None,
                 tweak: dict[str, dict] | None = None) -> None:
        from sim_models.dyno import RopeBenchConfig, RopeDynamometer

        self.plant = plant
        p = plant.params(tweak)
        cfg = config or RopeBenchConfig()
        self.config = cfg
        self.dyno = {a.name: RopeDynamometer(a, p, cfg) for a in p.axes}
        self.plan = SweepPlan(wheel_radius_m=cfg.wheel_radius_m, theta_deg=cfg.rope_angle_deg,
                              supply_v=p.bridge.supply_V)
        #: every reading's settle time and whether it converged, in order
        self.settle_log: list[dict] = []

    def axes(self) -> tuple[str, ...]:
        return tuple(self.dyno)

    def measure(self, axis: str, seed: int | None) -> Measure:
        import random

        if axis not in self.dyno:
            raise ValueError(f"axis {axis!r}: the plant has {list(self.dyno)}")
        d = self.dyno[axis]
        rng = None if seed is None else random.Random(f"{axis}:{seed}")

        def measure(w: PinWaveform) -> Reading:
            r = d.measure(w.segments, w.period_s, rng)
            self.settle_log.append({"axis": axis, "freq_hz": w.freq_hz, "duty_counts": w.duty_counts,
                                    "settle_s": r.trace.settle_s, "converged": r.trace.converged})
            # the ammeter shows a mean; PWM ripple is not "wandering", so no current_std_a column
            return Reading(force_n=r.force_N, current_a=r.current_A, settle_s=r.trace.settle_s)

        return measure


def simulate_lab(out_dir: Path, bench: LabBench, axes: Sequence[str] = ("x", "z"), seed: int | None = 0,
                 wf: Waveforms | None = None, th: Thresholds = Thresholds(), quiet: bool = False) -> dict[str, MotorResult]:
    """Every axis through the simulated bench: ``out_dir/<axis>/*.csv`` as a
    lab would hand them to ``torqueloop-study characterize run``."""
    wf = wf or Waveforms()
    out = {}
    for a in axes:
        tag = (f"simulated bench: plant {bench.plant.label}, {wf.source} pins, {wf.drive} off-phase, "
               f"motor {a}, instrument seed {seed}")
        out[a] = run_bench(bench.measure(a, seed), out_dir / a, a, bench.plan, th, wf=wf, tag=tag)
        if not quiet:
            _progress(f"{a} (seed {seed}): {out[a].status}: {out[a].message}")
    return out


def rope_config(settle: float | str = 0.3, **changes: object) -> "object":
    """The rope bench's configuration with a settle rule: a number is a fixed
    settle in seconds (the project's bench used 0.3 s); ``"converged"`` waits
    until the gauge's window mean has stopped moving (RopeBenchConfig's
    converge_frac of the stall force per window, converge_windows windows in
    a row) and records the time it took."""
    import dataclasses

    from sim_models.dyno import RopeBenchConfig

    if settle == "converged":
        return dataclasses.replace(RopeBenchConfig(), settle_rule="converged", **changes)
    if isinstance(settle, bool) or not isinstance(settle, (int, float)) or not settle > 0:
        raise ValueError(f"settle {settle!r}: a positive number of seconds or 'converged'")
    return dataclasses.replace(RopeBenchConfig(), settle_rule="fixed", settle_s=float(settle), **changes)


# ---------------------------------------------------------------- the paper's dead zone on the applied system


@dataclass(frozen=True)
class MotionRamp:
    """How the simulated lab finds the paper's dead zone (sec. II.B, "raise
    the pulse width until the system moves, lower it until it stops"): on
    the stage axis itself (motor, gearbox, screw, table; no dynamometer),
    from rest, the duty raised in steps of ``step_counts`` (of the 1023-count
    period), each held ``dwell_s``, until the motor-side encoder moves by
    ``threshold_counts`` within the last ``1 - settle_frac`` of a dwell; then
    lowered in the same steps until it does not.  Counting only the end of
    the dwell lets the rotor coast out of the previous step: a rotor that is
    still decelerating has not "stopped moving" and has not kept moving
    either."""

    step_counts: int = 4
    dwell_s: float = 0.2
    settle_frac: float = 0.5
    threshold_counts: int = 2
    max_duty_counts: int = 512


def _reverse(pins: tuple[int, int, int, int]) -> tuple[int, int, int, int]:
    return (pins[1], pins[0], pins[2], pins[3])


def record_motion_ramp(params: "object", axis_index: int, count_max: int, direction: int,
                       ramp: MotionRamp = MotionRamp()) -> tuple[list[float], list[int], list[float], list[int]]:
    """One ramp up and down on a plant axis (``params``: sim_models
    PlantParams) at the carrier of ``count_max``, brake off-phase, forward
    (+1) or reverse (-1): (duty % up, counts moved per dwell up, duty % down,
    counts moved down), what a lab writes down."""
    from sim_models.bridge import Pins
    from sim_models.stepper import FastAxis

    if direction not in (1, -1):
        raise ValueError(f"direction {direction!r}: +1 or -1")
    m = pwm_full_scale(PWM_BITS)
    fa = FastAxis(params.axes[axis_index], params, axis_index)  # type: ignore[attr-defined]
    edges: list = []

    def hold(duty_counts: int) -> int:
        w = model_waveform(count_max, duty_counts)
        n = max(2, int(np.ceil(ramp.dwell_s / w.period_s)))
        n_settle = min(n - 1, int(round(ramp.settle_frac * n)))
        segs = [(Pins(*(p if direction > 0 else _reverse(p))),
                 (w.segments[k + 1][0] if k + 1 < len(w.segments) else w.period_s) - t0)
                for k, (t0, p) in enumerate(w.segments)]
        c0 = fa.count
        for k in range(n):
            if k == n_settle:
                c0 = fa.count
            for p, dt in segs:
                fa.set_pins(p)
                fa.advance(dt, edges)
                edges.clear()
        return fa.count - c0

    up_d: list[float] = []
    up_m: list[int] = []
    d = 0
    while d + ramp.step_counts <= min(ramp.max_duty_counts, m):
        d += ramp.step_counts
        moved = hold(d)
        up_d.append(100.0 * d / m)
        up_m.append(moved)
        if abs(moved) >= ramp.threshold_counts:
            break
    down_d: list[float] = []
    down_m: list[int] = []
    if up_m and abs(up_m[-1]) >= ramp.threshold_counts:
        while d - ramp.step_counts >= 0:
            d -= ramp.step_counts
            moved = hold(d)
            down_d.append(100.0 * d / m)
            down_m.append(moved)
            if abs(moved) < ramp.threshold_counts:
                break
    return up_d, up_m, down_d, down_m


def motion_dead_zones(plant: Plant, freqs_hz: Sequence[float], axes: Sequence[str] = ("x", "z"),
                      ramp: MotionRamp = MotionRamp(), quiet: bool = True) -> list[MotionDeadZone]:
    """The paper's dead zone per axis, per direction, per carrier (the board
    carrier nearest each frequency) on a plant variant."""
    from sim_models.variants import load_variant

    p = load_variant(plant.name, plant.off)
    names = [a.name for a in p.axes]
    out = []
    for axis in axes:
        if axis not in names:
            raise ValueError(f"axis {axis!r}: the plant has {names}")
        i = names.index(axis)
        for f in freqs_hz:
            n = divider_for(f, CLK_HZ, PWM_BITS)
            f_board = model_waveform(n, 1).freq_hz
            for direction in (1, -1):
                rec = record_motion_ramp(p, i, n, direction, ramp)
                dz = motion_dead_zone(*rec, threshold_counts=ramp.threshold_counts, freq_hz=f_board,
                                      direction=direction)
                if not quiet:
                    _progress(f"{axis} {f_board:.4g} Hz dir {direction:+d}: moves from {dz.start_pct:.2f} %, "
                              f"stops below {dz.stop_pct:.2f} %")
                out.append(dz)
    return out
