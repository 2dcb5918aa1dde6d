# SPDX-License-Identifier: MIT
"""The paper's experiment (sec. VI.B, Figs 14-16, Table 3): two arms, as the paper has them.

From rest, a step of 6.28 rad (one screw turn, 4 mm) on both axes with P, PD
or PID and the Table 1 gains, for T seconds (the paper's 40 s):

* **model arm** (:func:`run_paper_model`): the paper's simulation - eq. (7)
  and (17) on the ``paper`` plant, the armature voltage averaged over the PWM
  period, no encoder quantisation (torqueloop.sim.model_loop.run_averaged);
* **experiment arm** (:func:`run_rtl`): the board image running the real servo
  firmware, configured over its UART the way a user configures the board
  (the characterisation file through the host tool's ``config load`` code
  path, then the law and gains), closing the loop only through its pins with
  a plant it does not know (``lab``) (:mod:`.pins`);
* **fast path** (:func:`run_fast`): the same board settings and plant with the
  firmware's law in Python (torqueloop/oracles/servo.py, the oracle of
  control.c) and the PWM block's event model; checked against the RTL arm
  law by law (the implementation check) before the variants and the
  frequency sweep run on it.

Time origin of every arm: the control sample at which the step set-point is
first used (RTL: the first telemetry frame whose set-point is the target;
the models: sample 0).  Sample j of one is compared with sample j of the other.
"""

from __future__ import annotations

import dataclasses
import math
import time
from dataclasses import asdict, dataclass, field

import numpy as np

from sim_models.params import PlantParams
from sim_models.stepper import TwoAxisPlant
from sim_models.variants import PlantSpec
from torqueloop.flow import firmware
from torqueloop.flow.manifest import REPO_ROOT
from torqueloop.host import config as hconfig
from torqueloop.host.client import Client
from torqueloop.sim.link import SimTransport, sim_client, telemetry
from torqueloop.sim.model_loop import TABLE1, LoopConfig, run_averaged
from torqueloop.sim.pins import PlantOnPins
from torqueloop.spec import auth
from torqueloop.spec import protocol as tp
from torqueloop.spec.pwm import carrier_hz, divider_for
from torqueloop.spec.system import SYSTEM

LAWS = {"P": 1, "PD": 2, "PID": 3}
CLK_HZ = SYSTEM.clk_hz
COUNTS_PER_REV = SYSTEM.counts_per_turn
#: the paper's tau_max (twice tau_max/2 of sec. VI.A), milli N m: the torque at full PWM command
TAU_MAX_MNM = tuple(a.tau_max_mnm for a in SYSTEM.axes)
BOARD_KEYS = ("FDIV", "PW0", "PWMAX", "TAU_MAX_MNM")
AXES = (0, 1)                 # x, z: every run drives both
BOTH_AXES = 0b11              # the axis mask of ENABLE and CLEAR_FAULT for both
#: the law's parameters a tuned run may set (protocol.toml name: torqueloop.oracles.servo.AxisParams field)
TUNED_FIELDS = {"LAW": "law", "KP_Q16": "kp_q16", "KD_Q16": "kd_q16", "KI_Q16": "ki_q16", "VEL_MODE": "vel_mode",
                "DEADBAND_Q16": "deadband_q16", "FC_POS": "fc_pos", "FC_NEG": "fc_neg", "IZONE_Q16": "izone_q16",
                "KVFF_Q16": "kvff_q16", "KAFF_Q16": "kaff_q16", "DITHER_AMP": "dither_amp",
                "DITHER_HALF": "dither_half", "VMAX": "vmax_cps", "AMAX": "amax_cps2"}


@dataclass(frozen=True)
class HarnessTiming:
    """What the harness waits for on the board image, named once."""

    reset_clk: int = 20             # clocks in reset, arm switch down
    arm_delay_clk: int = 40_000     # out of reset with the switch down, before it rises (0.8 ms)
    settle_ms: int = 30             # after configuring: past a deadline of the previous control period
    sample_poll_clk: int = 2_000    # the step waits for a fresh sample in strides of this
    loop_poll_clk: int = 20_000     # run_fast_loop's stride between link polls
    link_timeout_ms: int = 2_000    # LINK_TIMEOUT_MS of a run (the heartbeat feeds it every heartbeat_s)
    follow_limit_turns: int = 10    # FOLLOW_LIMIT in screw turns: axis z overshoots by most of a turn


TIMING = HarnessTiming()


@dataclass(frozen=True)
class ExperimentConfig:
    law: str = "P"
    t_end_s: float = SYSTEM.t_end_s     # the paper's T
    step_rad: float = SYSTEM.step_rad   # one screw turn, 4 mm (sec. VI.B)
    period_us: int = SYSTEM.period_us   # control period: the paper's 25 ms speed sample period
    plant: PlantSpec = PlantSpec("paper")   # plant variant, effects off (sim_models.variants.plant_of)
    char_config: str | None = None      # characterisation file, loaded as `torqueloop config load` does
    pwm_hz: tuple[float, ...] | None = None   # carriers set after the file (None: the file's, else the paper's)
    pw0_off: bool = False               # PW0 set to 0 after the file: no dead-zone compensation
    pw0_counts: tuple[int, ...] | None = None   # PW0 per axis set after the file (a dead zone measured elsewhere)
    start_counts: tuple[int, ...] = (0, 0)  # fast path: a move to here first (for start_s), then the step from it
    start_s: float = 2.0
    record_s: float = 0.002             # grid of the plant trace (plots)
    heartbeat_s: float = 0.25           # HEARTBEAT, as the host tool keeps the link watchdog fed
    brake: bool = True                  # off-phase: brake (slow decay), as pwm_torque drives the IBT-2
    baud_div: int | None = None         # UART clocks per bit - 1 after IDENTIFY (None: keep 115200,
                                        # the RN-XV's rate); short control periods need a faster link
    progress: bool = True
    #: per axis, raw board settings written after the Table 1 law and gains, which they replace
    #: (``torqueloop tune --verify``: LAW, KP_Q16, KD_Q16, KI_Q16, PW0, FDIV, VEL_MODE); None: the paper's
    tuned: tuple[dict[str, int], ...] | None = None
    #: the move: the paper's step (MOVE mode 0), or the trapezoid profile (mode 1) at each axis's VMAX and AMAX
    trapezoid: bool = False

    @property
    def target_counts(self) -> int:
        return round(self.step_rad * COUNTS_PER_REV / (2 * math.pi))

    def plant_params(self) -> PlantParams:
        return self.plant.params()

    def loaded_settings(self) -> tuple[dict[str, int], ...]:
        """What ``config load`` of the characterisation file writes (per axis
        FDIV, PW0, PWMAX, TAU_MAX_MNM), through the host tool's own reader;
        without a file the board's defaults (the paper's carriers and tau_max)."""
        if self.char_config is not None:
            hc = hconfig.load_file(self.char_config)
            return tuple({k: ax[k] for k in BOARD_KEYS} for ax in hc.axes)
        return tuple({"FDIV": divider_for(f), "PW0": 0, "PWMAX": SYSTEM.pwm_full, "TAU_MAX_MNM": t}
                     for f, t in zip(SYSTEM.pwm_hz, TAU_MAX_MNM))

    def overrides(self) -> tuple[dict[str, int], ...]:
        """What the user sets after loading (``torqueloop set pwm_freq F``, ``set pw0 0``)."""
        out: list[dict[str, int]] = [{} for _ in AXES]
        for ax in AXES:
            if self.pwm_hz is not None:
                out[ax]["FDIV"] = divider_for(self.pwm_hz[ax])
            if self.pw0_counts is not None:
                out[ax]["PW0"] = int(self.pw0_counts[ax])
            if self.pw0_off:
                out[ax]["PW0"] = 0
            if self.tuned is not None:
                out[ax] |= {k: v for k, v in self.tuned[ax].items() if k in BOARD_KEYS}
        return tuple(out)

    def law_settings(self, ax: int) -> dict[str, int]:
        """The law's raw settings of an axis beyond the board's (the tuned ones), written last."""
        return {} if self.tuned is None else {k: v for k, v in self.tuned[ax].items() if k not in BOARD_KEYS}

    def board(self) -> tuple[dict[str, int], ...]:
        """The settings the board runs with, per axis."""
        return tuple(l | o for l, o in zip(self.loaded_settings(), self.overrides()))

    def profile(self, ax: int) -> tuple[int, int]:
        """VMAX (counts/s) and AMAX (counts/s^2) of an axis's trapezoid: the tuned ones, else the board's defaults."""
        t = {} if self.tuned is None else self.tuned[ax]
        return (t.get("VMAX", tp.PARAMS["VMAX"].defaults[ax]), t.get("AMAX", tp.PARAMS["AMAX"].defaults[ax]))

    @property
    def fdiv(self) -> tuple[int, ...]:
        return tuple(b["FDIV"] for b in self.board())

    @property
    def pwm_hz_actual(self) -> tuple[float, ...]:
        return tuple(carrier_hz(d) for d in self.fdiv)


@dataclass
class Trajectory:
    """Samples at the control instants, j = 0 at the step; SI units (rad, rad/s)."""
    t: np.ndarray              # (n,)
    pos: np.ndarray            # (n, 2) measured position (encoder; the model arm: unquantised)
    vel: np.ndarray            # (n, 2) the controller's velocity estimate
    cmd: np.ndarray            # (n, 2) PWM command, -1023..1023
    err: np.ndarray            # (n, 2) tracking error: set-point - position (the firmware's, rounded to counts)
    true_pos: np.ndarray       # (n, 2) plant screw angle at the sample
    charge: np.ndarray | None = None   # (n, 2) integral of the armature current since the step, A s
    i2: np.ndarray | None = None       # (n, 2) integral of its square, A^2 s


@dataclass
class RtlRun:
    config: ExperimentConfig
    traj: Trajectory
    trace_t: np.ndarray        # plant trace (s, same origin), fine grid
    trace_pos: np.ndarray      # screw angle, rad
    trace_vel: np.ndarray      # screw speed, rad/s
    trace_current: np.ndarray  # A
    cycles: int = 0            # clocks simulated in total (start-up and configuration included)
    wall_s: float = 0.0
    cpu_s: float = 0.0
    t0_jitter_s: float = 0.0   # spread of the telemetry latency used to place the samples on the plant trace
    identify: dict = field(default_factory=dict)
    bridge: dict = field(default_factory=dict)
    faults: list[int] = field(default_factory=list)
    config_faults: list[int] = field(default_factory=list)   # latched by the configuration, cleared
    link_errors: int = 0
    uart_errors: int = 0
    board: tuple = ()          # the settings read back from the board after configuring
    resistance_ohm: tuple = () # winding resistance per axis (copper loss)
    #: per axis, clocks from the step's sample to the first period start that
    #: drives the bridge (the carrier's phase; None: it never drove)
    carrier_start_clk: tuple = ()


def firmware_image(key: bytes | None = auth.TEST_KEY) -> firmware.Image:
    """The real servo firmware, as make firmware builds it, behind a boot-ROM
    stub whose key slot holds ``key`` (the public test key by default: the
    experiment configures the board over its link, which needs one)."""
    return firmware.build("servo", out=REPO_ROOT / "build" / "rtl_loop" / "firmware", key=key)


def configure(link: Client, cfg: ExperimentConfig) -> list[dict[str, int]]:
    """Configure the board as a user does: ``torqueloop config load`` of the
    characterisation file (the host tool's reader and write order), then
    ``set`` for any override, the law and the Table 1 gains in the protocol's
    physical units (the firmware converts them with the loaded tau_max).
    Returns the board settings read back."""
    if cfg.char_config is not None:
        for axis, name, value in hconfig.apply_order(hconfig.load_file(cfg.char_config)):
            link.set_param(name, value, axis)
    else:
        for ax, b in enumerate(cfg.loaded_settings()):
            for k, v in b.items():
                link.set_param(k, v, ax)
    for ax, o in enumerate(cfg.overrides()):
        for k, v in o.items():
            link.set_param(k, v, ax)
    link.set_param("PERIOD_US", cfg.period_us)
    link.set_param("LINK_TIMEOUT_MS", TIMING.link_timeout_ms)
    for ax in AXES:
        link.set_param("COUNTS_PER_REV", COUNTS_PER_REV, ax)
        _set_law(link, cfg.law, ax)
        link.set_param("CMD_LIMIT", SYSTEM.pwm_full, ax)
        link.set_param("VEL_MODE", 0, ax)          # the paper's filtered Euler difference
        link.set_param("BRAKE", int(cfg.brake), ax)
        link.set_param("FOLLOW_LIMIT", TIMING.follow_limit_turns * COUNTS_PER_REV, ax)
        for k, v in cfg.law_settings(ax).items():
            link.set_param(k, v, ax)
    return [{k: link.get_param(k, ax) for k in BOARD_KEYS} for ax in AXES]


def power_up(board, bridge: PlantOnPins, host_nonce: bytes | None = None) -> tuple[Client, dict[str, int]]:
    """The board image from reset to a link in an authenticated session:
    reset with the arm switch down, release, then arm (SW[0] rising edge),
    IDENTIFY, SESSION under the public test key the stub ROM holds.  Returns
    the host tool's client on the board's UART and IDENTIFY's reply.  ``host_nonce``: fixed, for runs that must
    repeat byte for byte."""
    board.set_board(0, 1, 0)
    bridge.run_to(TIMING.reset_clk)
    board.set_board(1, 1, 0)
    bridge.run_to(TIMING.arm_delay_clk)
    board.set_board(1, 1, 1)
    link = sim_client(SimTransport(board.uart_send, board.uart_recv, lambda n: bridge.run_to(board.cycle + n),
                                   lambda: board.cycle), auth.TEST_KEY)
    ident = link.connect()
    link.open_session(host_nonce)
    return link, ident


def run_rtl(cfg: ExperimentConfig, board_factory=None, log=print) -> RtlRun:
    """Run the experiment on the board image; ``board_factory(rom, ram)``
    gives a :class:`~torqueloop.sim.pins.BoardPort` (default: native Verilator)."""
    from torqueloop.sim.native import NativeBoard
    img = firmware_image()
    board = (board_factory or NativeBoard.create)(img.rom_hex, img.ram_hex)
    params = cfg.plant_params()
    plant = TwoAxisPlant(params, seed=0, energy=True)
    bridge = PlantOnPins(plant, board)
    w0, c0 = time.monotonic(), time.process_time()
    try:
        link, ident = power_up(board, bridge)
        if cfg.baud_div is not None:
            link.set_param("BAUD_DIV", cfg.baud_div)   # replied at the old rate
            board.set_uart_div(cfg.baud_div + 1)
        settings = configure(link, cfg)
        # Wait past a deadline of the previous control period and record
        # anything latched: a firmware that kept its tick at the old period's
        # deadline after PERIOD_US changes would trip the SoC watchdog here,
        # which shows in report.json and fails the rtl_loop test.
        link.transport.advance(TIMING.settle_ms * CLK_HZ // 1000)
        config_faults = [link.status(ax)["faults"] for ax in AXES]
        if any(config_faults):
            link.clear_fault(BOTH_AXES)
        link.set_telemetry(1)
        link.enable(BOTH_AXES)
        # step both axes in the same control period: send both MOVEs right after a sample
        n_tel = len(link.telemetry_queue)
        while len(link.telemetry_queue) == n_tel:
            link.transport.advance(TIMING.sample_poll_clk)
            link.poll()
        target = cfg.target_counts
        # the paper's step from rest, relative to where the stage was at power-up: UNHOMED
        bridge.watch(board.cycle)       # the first drive edges give the carriers' phase at the step
        mode = tp.MOVE_UNHOMED | (tp.MOVE_TRAPEZOID if cfg.trapezoid else 0)
        seqs = [link.post("MOVE", axis=ax, mode=mode, target=target) for ax in AXES]
        for s in seqs:
            r = link.wait(s)
            if r["status"] != tp.STATUS["OK"]:
                raise RuntimeError(f"MOVE refused: {tp.STATUS_NAME[r['status']]}")
        move_cycle = board.cycle
        period_cycles = cfg.period_us * CLK_HZ // 1_000_000
        end = move_cycle + round(cfg.t_end_s * CLK_HZ) + 3 * period_cycles
        rec = max(1, round(cfg.record_s * CLK_HZ))
        hb = round(cfg.heartbeat_s * CLK_HZ)
        next_hb = board.cycle + hb
        trace: list[tuple] = []
        next_print = time.monotonic() + 2.0
        sim0 = board.cycle
        while board.cycle < end:
            bridge.run_to(min(end, board.cycle + rec))
            trace.append((board.cycle, plant.screw_angle(0), plant.screw_angle(1), plant.screw_speed(0),
                          plant.screw_speed(1), plant.current(0), plant.current(1),
                          plant.charge(0), plant.charge(1), plant.current_sq_integral(0),
                          plant.current_sq_integral(1)))
            link.poll()
            if board.cycle >= next_hb:
                link.post("HEARTBEAT")
                next_hb += hb
            if cfg.progress and time.monotonic() >= next_print:
                next_print += 5.0
                wall = time.monotonic() - w0
                done = (board.cycle - move_cycle) / CLK_HZ
                speed = (board.cycle - sim0) / max(1e-9, time.monotonic() - w0)
                log(f"  [{cfg.law}] sim {done:6.2f} / {cfg.t_end_s:.1f} s  wall {wall:6.1f} s  "
                    f"{speed / 1e6:5.2f} Mcycle/s  ({speed / CLK_HZ:5.3f} x real time)", flush=True)
        link.poll()
        run = _assemble(cfg, link, trace, target, bridge.watched)
        run.cycles = board.cycle
        run.identify = ident
        run.config_faults = config_faults
        run.uart_errors = board.uart_errors() if hasattr(board, "uart_errors") else 0
        run.link_errors = link.stats.crc_errors + link.stats.bad_chunks
        run.bridge = asdict(bridge.stats)
        run.board = tuple(settings)
        run.resistance_ohm = tuple(a.resistance_ohm for a in params.axes)
    finally:
        if hasattr(board, "close"):
            board.close()
    run.wall_s = time.monotonic() - w0
    run.cpu_s = time.process_time() - c0
    return run


def _assemble(cfg: ExperimentConfig, link: Client, trace: list[tuple], target: int,
              pin_changes: list[list[int]]) -> RtlRun:
    """Each axis's samples from the first control iteration that used the
    step's target: the first frame whose error is target - position (the
    error is the iteration's; a frame is built after its iteration, so a MOVE
    that arrives in between shows in its setpoint too early).  The two MOVEs
    may straddle a sample (two authenticated frames take ~7 ms at 115 200
    baud): each axis is then aligned on its own step."""
    tel = telemetry(link)
    n = int(round(cfg.t_end_s * 1e6 / cfg.period_us)) + 1
    # place the samples on the plant's clock: a sample at firmware time time_us
    # leaves its first telemetry byte L clocks later; the smallest latency seen
    # is taken as the sample instant (the spread is reported)
    off = np.array([f.cycle - f.time_us * (CLK_HZ // 1_000_000) for f in tel[1:]], float)
    base = off.min()
    tr = np.array(trace, float)
    t = np.arange(n) * cfg.period_us * 1e-6
    rad = 2 * math.pi / COUNTS_PER_REV
    cols: dict[str, list[np.ndarray]] = {k: [] for k in ("pos", "vel", "cmd", "err", "true", "q", "q2")}
    start, tts, k0s = [], [], []
    for a in AXES:
        k0 = _first_sample(cfg, tel, a, target)
        if k0 is None:
            raise RuntimeError(f"no telemetry frame of axis {a} shows an iteration that used the step's target")
        sel = tel[k0:k0 + n]
        k0s.append(k0)
        if len(sel) < n:
            raise RuntimeError(f"only {len(sel)} of {n} control samples arrived")
        if [(f.time_us - sel[0].time_us) // cfg.period_us for f in sel] != list(range(n)):
            raise RuntimeError("telemetry frames missing (the firmware dropped some)")
        ax = [f.axes[a] for f in sel]
        cols["pos"].append(np.array([x["position"] for x in ax], float) * rad)
        cols["vel"].append(np.array([x["velocity_q8"] for x in ax], float) / 256 * rad)
        cols["cmd"].append(np.array([x["pwm_cmd"] for x in ax], float))
        cols["err"].append(np.array([x["error"] for x in ax], float) * rad)
        c_step = base + sel[0].time_us * (CLK_HZ // 1_000_000)
        tt = (tr[:, 0] - c_step) / CLK_HZ
        for k, col in (("true", 1), ("q", 7), ("q2", 9)):
            cols[k].append(np.interp(t, tt, tr[:, col + a]))
        tts.append(tt)
        # the first pin change after the MOVE is the first period start that
        # takes the step's command; at least 1 clock, so that the fast path's
        # carrier takes the command loaded at the sample
        start.append(max(1, round(pin_changes[a][0] - c_step)) if pin_changes[a] else None)
    pos, vel, cmd, err, true_pos, charge, i2 = (np.stack(cols[k], axis=1)
                                                for k in ("pos", "vel", "cmd", "err", "true", "q", "q2"))
    faults = sorted({x["faults"] for f in tel[min(k0s):max(k0s) + n] for x in f.axes})
    tt = tts[0]                      # the plant trace on axis x's step clock
    keep = tt >= -0.1
    traj = Trajectory(t, pos, vel, cmd, err, true_pos, charge - charge[0], i2 - i2[0])
    return RtlRun(cfg, traj, tt[keep], tr[keep][:, 1:3], tr[keep][:, 3:5], tr[keep][:, 5:7],
                  t0_jitter_s=float(np.percentile(off, 95) - base) / CLK_HZ, faults=faults,
                  carrier_start_clk=tuple(start))


def _first_sample(cfg: ExperimentConfig, tel: list, a: int, target: int) -> int | None:
    """The telemetry frame of the first iteration that used the move.  A step: the first
    whose error is target - position.  A trapezoid starts where the axis stands, so its first
    samples look like the hold before it: the first frame whose set-point (floor of the
    profile's, as the firmware reports it) left the hold's, less the samples the firmware's
    profile (its oracle, bit for bit) takes to leave it."""
    if not cfg.trapezoid:
        return next((i for i, f in enumerate(tel) if f.axes[a]["error"] == target - f.axes[a]["position"]), None)
    from torqueloop.oracles.servo import Axis, AxisParams
    s0 = tel[0].axes[a]["setpoint"]
    j1 = next((i for i, f in enumerate(tel) if f.axes[a]["setpoint"] != s0), None)
    vmax, amax = cfg.profile(a)
    ref = Axis(AxisParams(vmax_cps=vmax, amax_cps2=amax), cfg.period_us)
    ref.reset(s0, 0)
    ref.move(target, True)
    m1 = 0
    while True:
        ref.step(s0, 0, 0, run=False)
        if ref.sp_q16 >> 16 != s0 or not ref.moving:
            break
        m1 += 1
    return None if j1 is None or j1 < m1 else j1 - m1


@dataclass
class ModelRun:
    traj: Trajectory
    wall_s: float
    config: dict
    resistance_ohm: tuple = ()


def run_paper_model(cfg: ExperimentConfig) -> ModelRun:
    """The model arm: the paper's simulation (model_loop.run_averaged) on
    ``cfg.plant`` with the paper's tau_max in the scaling (eq. 23-25), the
    Table 1 gains and the firmware's anti-windup (the paper's firmware law is
    unknown; the same law in both arms keeps the comparison about the plant
    and the drive, not the integrator).  With ``cfg.char_config`` the scaling
    takes the tau_max the file sets instead (what ``config load`` writes: the
    measured stall torque), the plant unchanged: the Table 3 decomposition's
    ``measured_tau_max`` row."""
    params = cfg.plant_params()
    target_rad = cfg.target_counts * 2 * math.pi / COUNTS_PER_REV
    lc = LoopConfig(setpoint_rad=target_rad, t_end_s=cfg.t_end_s, sample_s=cfg.period_us * 1e-6,
                    gains=TABLE1[cfg.law])
    scaling = params
    if cfg.char_config is not None:
        scaling = dataclasses.replace(params, axes=tuple(
            a.replace(tau_max_paper_N_m=s["TAU_MAX_MNM"] / 1000.0) for a, s in zip(params.axes, cfg.loaded_settings())))
    r = run_averaged(lc, scaling, TwoAxisPlant(params, seed=0))
    traj = Trajectory(r.t, r.x_meas, r.v_est, r.cmd, target_rad - r.x_meas, r.x_true)
    return ModelRun(traj, r.wall_s, {"arm": "model", "plant": cfg.plant.label, "law": cfg.law, "drive": "averaged voltage",
                                     "gains": [asdict(g) for g in lc.gains]},
                    tuple(a.resistance_ohm for a in params.axes))


def run_fast(cfg: ExperimentConfig, carrier_start_clk: tuple = (), edges: bool = False) -> ModelRun:
    """The fast path: the board's settings (``cfg.board()``) and plant with
    the *firmware's* law in Python (torqueloop/oracles/servo.py, the oracle of
    firmware/servo/control.c: fixed point, anti-windup, deadband, dead-zone
    compensation by the PWM block) and the PWM block's event model
    (torqueloop.oracles.pwm_schedule).  No RTL, CPU or pins: between this and
    the RTL arm the difference is the implementation (the implementation
    check); copper loss and current ripple come from the plant's exact
    current integrals.  ``carrier_start_clk``: per axis, the clock of the
    first period start after the step's sample (an RTL run's
    ``carrier_start_clk``, for the implementation check); by default a
    period starts at the sample, before its command is loaded, so the step
    drives one carrier period later (the latest the board can).

    Each control period the plant takes every pin change of the period at
    once (``TwoAxisPlant.run_pins``: its guards checked for many chunks in
    one product, no encoder edges, docs/plant.md "The fast path");
    ``edges=True`` steps it edge by edge as the co-simulation does
    (``run_until``), the reference that stepping is checked against."""
    from torqueloop.oracles.pwm_schedule import PwmChannel, PwmSetting, run_pins_until, run_until
    from torqueloop.oracles.servo import Axis, AxisParams
    from torqueloop.spec.bridge import BRAKE, COAST
    params = cfg.plant_params()
    plant = TwoAxisPlant(params, seed=0, energy=True)
    period = cfg.period_us * CLK_HZ // 1_000_000
    safe = BRAKE if cfg.brake else COAST
    board = cfg.board()
    setting = [dict(div=b["FDIV"], pw0=b["PW0"], pwmax=b["PWMAX"], safe=safe) for b in board]
    starts = [s or 0 for s in carrier_start_clk] or [0, 0]
    channels = [PwmChannel(PwmSetting(**st), off_phase=safe, first_start=s) for st, s in zip(setting, starts)]
    axes = []
    for ax in AXES:
        g = TABLE1[cfg.law][ax]
        raw = [tp.gain_raw_from_phys(round(k * 1e6), board[ax]["TAU_MAX_MNM"], COUNTS_PER_REV) if k else 0
               for k in (g.kp, g.kd, g.ki)]
        ap = AxisParams(law=LAWS[cfg.law], kp_q16=raw[0], kd_q16=raw[1], ki_q16=raw[2], vel_mode=0)
        tuned = cfg.law_settings(ax)
        if tuned:
            ap = dataclasses.replace(ap, **{TUNED_FIELDS[k]: v for k, v in tuned.items() if k in TUNED_FIELDS})
        a = Axis(ap, cfg.period_us)
        a.reset(0, 0)
        axes.append(a)
    n = int(round(cfg.t_end_s * 1e6 / cfg.period_us)) + 1
    # a start away from 0: the same law moves there first, so the step begins where (and from the side) it arrived
    n_pre = int(round(cfg.start_s * 1e6 / cfg.period_us)) if any(cfg.start_counts) else 0
    out = {k: np.zeros((n, 2)) for k in ("pos", "vel", "cmd", "err", "true", "q", "q2")}
    q0, q20 = [0.0, 0.0], [0.0, 0.0]
    w0 = time.monotonic()
    edge_clk, edge_gap = [0, 0], [0, 0]      # the decoder's last edge and the interval before it (VEL_MODE 1)
    # the edge-timestamp speed (VEL_MODE 1, a tuned setting) needs the decoder's edge times, which only
    # edge-by-edge stepping produces; the per-period stepping has no encoder edges
    step_edges = edges or any(a.p.vel_mode for a in axes)

    def on_edges(start: int, edges: list) -> None:
        for e in edges:
            at = start + int(e.t * CLK_HZ)
            edge_gap[e.axis], edge_clk[e.axis] = at - edge_clk[e.axis], at

    for kk in range(n_pre + n):
        ts, k = kk * period, kk - n_pre
        prev = (kk - 1) * period if kk else 0
        if step_edges:
            run_until(plant, channels, prev, ts, CLK_HZ, on_edges)
        else:
            run_pins_until(plant, channels, prev, ts, CLK_HZ)
        for a in AXES:
            if kk == 0 and n_pre:
                axes[a].move(cfg.start_counts[a], False)
            if k == 0:
                axes[a].move(cfg.start_counts[a] + cfg.target_counts, cfg.trapezoid)
                q0[a], q20[a] = plant.charge(a), plant.current_sq_integral(a)   # the step's own current
            pos = plant.count(a)
            cmd = axes[a].step(pos, edge_clk[a] & 0xFFFF_FFFF, ts & 0xFFFF_FFFF, interval=min(edge_gap[a], 0xFFFF_FFFF))
            channels[a].load(PwmSetting(cmd=cmd, **setting[a]))
            if k < 0:
                continue
            out["pos"][k, a] = pos - cfg.start_counts[a]
            out["vel"][k, a] = axes[a].vel_q8 / 256
            out["cmd"][k, a] = cmd
            out["err"][k, a] = (axes[a].sp_q16 - (pos << 16) + 0x8000) >> 16     # as the firmware reports it
            out["true"][k, a] = plant.screw_angle(a) - cfg.start_counts[a] * 2 * math.pi / COUNTS_PER_REV
            out["q"][k, a] = plant.charge(a) - q0[a]
            out["q2"][k, a] = plant.current_sq_integral(a) - q20[a]
    rad = 2 * math.pi / COUNTS_PER_REV
    t = np.arange(n) * cfg.period_us * 1e-6
    traj = Trajectory(t, out["pos"] * rad, out["vel"] * rad, out["cmd"], out["err"] * rad, out["true"],
                      out["q"], out["q2"])
    return ModelRun(traj, time.monotonic() - w0,
                    {"arm": "fast path", "plant": cfg.plant.label, "law": cfg.law, "board": list(board),
                     "carrier_start_clk": starts,
                     "pwm_hz": list(cfg.pwm_hz_actual), "implementation": "torqueloop.oracles.servo (firmware law)",
                     "plant_stepping": "edge by edge" if edges else "per control period"},
                    tuple(a.resistance_ohm for a in params.axes))


@dataclass
class FastLoopRun:
    """The control loop at a short period on the board image (docs/firmware.md, Timing)."""
    period_us: int
    seconds: float
    baud: float
    telemetry_every: int
    loop_cycles_max: int           # worst control iteration (mcycle, the firmware's STATUS)
    jitter_cycles_max: int         # worst lateness of the timer interrupt
    frames: int                    # telemetry frames received over the run
    frames_expected: int
    frames_missing: int            # gaps in the frames' time stamps
    tx_dropped: int                # frames the firmware could not queue (COUNTERS)
    faults: list[int]
    moved_counts: list[int]        # encoder counts travelled per axis during the run
    cycles: int = 0
    cpu_s: float = 0.0


def _set_law(link, law: str, ax: int) -> None:
    """``law`` and its Table 1 gains on axis ``ax`` (the protocol's units: Gains.micro)."""
    kp, kd, ki = TABLE1[law][ax].micro()
    link.set_param("LAW", LAWS[law], ax)
    link.set_param("KP_UNM_RAD", kp, ax)
    link.set_param("KD_UNMS_RAD", kd, ax)
    link.set_param("KI_UNM_RADS", ki, ax)


def run_fast_loop(period_us: int = 50, seconds: float = 0.5, law: str = "PID", baud_div: int = 53,
                  telemetry_every: int = 20, travel_counts: int = SYSTEM.counts_per_turn, move_mode: int = 0,
                  board_factory=None) -> FastLoopRun:
    """Both axes under ``law`` (Table 1 gains) at ``period_us`` (50 us: 20 kHz)
    on the board image with the plant on the pins, edge-timestamp velocity
    (VEL_MODE 1), moves of ``travel_counts`` (a screw turn) in opposite
    directions started at once (``move_mode`` 0: steps, 1: trapezoids); the link at ``50 MHz / (baud_div + 1)`` (53: 925 926 baud, what the
    RN-XV's 921 600 setting gives) with one telemetry frame every
    ``telemetry_every`` periods.  After ``seconds`` of motion STATUS gives
    the worst iteration and interrupt lateness, COUNTERS the dropped frames."""
    from torqueloop.sim.native import NativeBoard
    img = firmware_image()
    board = (board_factory or NativeBoard.create)(img.rom_hex, img.ram_hex)
    plant = TwoAxisPlant(ExperimentConfig().plant_params(), seed=0)
    bridge = PlantOnPins(plant, board)
    c0 = time.process_time()
    try:
        link, _ = power_up(board, bridge)
        link.set_param("BAUD_DIV", baud_div)
        board.set_uart_div(baud_div + 1)
        link.set_param("PERIOD_US", period_us)
        # the run sends nothing that feeds the link watchdog for `seconds`
        link.set_param("LINK_TIMEOUT_MS", max(500, round(seconds * 2000)))
        for ax in AXES:
            _set_law(link, law, ax)
            link.set_param("VEL_MODE", 1, ax)
        link.enable(BOTH_AXES)
        start = [link.status(ax)["position"] for ax in AXES]
        for ax in AXES:
            link.move(ax, start[ax] + travel_counts * (1 - 2 * ax), trapezoid=move_mode == 1, unhomed=True)
        link.set_telemetry(telemetry_every)
        n0 = len(link.telemetry_queue)
        t_end = board.cycle + round(seconds * CLK_HZ)
        while board.cycle < t_end:
            link.transport.advance(min(TIMING.loop_poll_clk, t_end - board.cycle))
            link.poll()
        frames = telemetry(link)[n0:]
        link.set_telemetry(0)
        st = [link.status(ax) for ax in AXES]
        cnt = link.counters()
        cycles = board.cycle
    finally:
        if hasattr(board, "close"):
            board.close()
    step_us = period_us * telemetry_every
    gaps = sum(max(0, (b.time_us - a.time_us) // step_us - 1) for a, b in zip(frames, frames[1:]))
    return FastLoopRun(period_us, seconds, CLK_HZ / (baud_div + 1), telemetry_every, st[0]["loop_cycles_max"],
                       st[0]["jitter_cycles_max"], len(frames), int(seconds * 1e6 / step_us), gaps,
                       cnt["tx_dropped"], [s["faults"] for s in st],
                       [abs(s["position"] - p0) for s, p0 in zip(st, start)], cycles,
                       time.process_time() - c0)
