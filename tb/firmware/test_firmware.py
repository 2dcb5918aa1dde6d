# SPDX-License-Identifier: MIT
"""firmware: the servo firmware (firmware/servo) on the whole simulated SoC.

The image is built by torqueloop.flow.firmware with test defaults (1 Mbaud
link so frames take microseconds, not milliseconds; 500 us control period)
and loaded through RAM_INIT; the boot ROM stub jumps to it.  The bench talks
to it only through the pins: the link protocol on uart_rx/uart_tx
(cocotbext-uart + torqueloop.spec.protocol, the host tool's own codec), encoder
quadrature on enc_a/enc_b, e-stop and bridge-fault inputs, and it watches the
bridge pins rpwm/lpwm/r_en/l_en.  Expected PWM commands come from
torqueloop/oracles/servo.py (the control law in Python integers).

The stub ROM's key slot holds auth.TEST_KEY; the bench opens a session after
boot and sends every command but the reads with its MAC, as the host tool
does (docs/security.md).  ``authentication_at_the_pins`` checks who may
drive the pins; ``no_key_board_refuses_motion`` runs on the same model with
the key slot blanked in the model's ROM.

Verilator only: the firmware needs a few hundred thousand clocks per test,
which Icarus runs ~30x slower (minutes per test).
"""

from __future__ import annotations

import json
import os
import random
from pathlib import Path

import cocotb
import pytest
from cocotb.queue import Queue
from cocotb.triggers import ClockCycles, Edge, First, Timer, with_timeout
from cocotb.utils import get_sim_time

from torqueloop.spec import auth
from torqueloop.spec import protocol as P
from torqueloop.oracles import servo as ref
from torqueloop.flow import firmware
from torqueloop.flow.tb_images import SERVO_TB_BAUD_DIV, SERVO_TB_PERIOD_US, TB_KEY, servo_tb_image

import tbutil

CLK_NS = 20
BAUD = 1_000_000
BAUD_DIV = SERVO_TB_BAUD_DIV       # 50 MHz / 1 Mbaud - 1 (flow/tb_images.py)
PERIOD_US = SERVO_TB_PERIOD_US
STEP_NS = 4000                     # encoder state time: well above the 3 us filter
QUAD = [(0, 0), (1, 0), (1, 1), (0, 1)]   # A leads B: counts up
FAST_FDIV = 2                      # 24.4 kHz: the fastest carrier under the IBT-2's 25 kHz rating (PWM_MAX_HZ)
PWM_PERIOD_US = FAST_FDIV * 1023 * CLK_NS / 1000
U = P.MOVE_UNHOMED                 # positions relative to power-up: these tests do not home
KEY = TB_KEY


def now_ns() -> float:
    return get_sim_time(unit="ns")


class TB:
    def __init__(self, dut) -> None:
        self.dut = dut
        self.seq = 0
        self.replies: Queue = Queue()
        self.telemetry: list[tuple[int, dict]] = []
        self.errors: list[P.Frame] = []
        self.enc = [0, 0]
        self.reply_timeout_us = 5000      # a SESSION takes ~1.5 ms (docs/security.md)
        tbutil.start_clock(dut, CLK_NS)
        tbutil.idle_soc_pins(dut)
        self.src, self.sink = tbutil.uart_models(dut.uart_rx, dut.uart_tx, BAUD, quiet=True)
        self.dec = P.FrameDecoder()
        self.sess: auth.Session | None = None
        self.sent: list[bytes] = []
        self.reply_ns = 0.0

    async def start(self, session: bool = True) -> None:
        self.dut.rst.value = 1
        await ClockCycles(self.dut.clk, 5)
        self.dut.rst.value = 0
        cocotb.start_soon(self._reader())
        await Timer(2 * PERIOD_US + 1500, unit="us")   # boot (the key's setup ~1.1 ms), first control periods
        if session:
            await self.open_session()

    async def open_session(self, expect: int = P.STATUS["OK"]) -> dict:
        hn = auth.new_host_nonce()
        r = await self.cmd("SESSION", expect, host_nonce=hn)
        if r["status"] == P.STATUS["OK"]:
            self.sess = auth.open_session(KEY, hn, r)
        return r

    async def _reader(self) -> None:
        while True:
            data = await self.sink.read()
            for f in self.dec.feed(bytes(data)):
                if isinstance(f, P.FrameError):
                    raise AssertionError(f"firmware sent a bad frame: {f}")
                if f.cmd == P.TELEMETRY_CMD:
                    self.telemetry.append((now_ns(), P.decode_telemetry(f)))
                elif f.cmd == P.ERROR_CMD:
                    self.errors.append(f)
                else:
                    self.reply_ns = now_ns()
                    await self.replies.put(f)

    async def send_raw(self, data: bytes) -> None:
        await self.src.write(data)
        await self.src.wait()

    async def cmd(self, name: str, expect: int | None = P.STATUS["OK"], tagged: bool | None = None,
                  **fields) -> dict:
        """One command and its reply; with the session's MAC unless it is a read (tagged overrides)."""
        self.seq = (self.seq + 1) & 0xFFFF
        tag = (self.sess is not None and not P.COMMANDS[name].untagged) if tagged is None else tagged
        wire = self.sess.request(name, self.seq, **fields) if tag else P.request(name, self.seq, **fields)
        self.sent.append(wire)
        await self.send_raw(wire)
        try:
            f = await with_timeout(self.replies.get(), self.reply_timeout_us, "us")
        except Exception:
            raise AssertionError(f"no reply to {name} seq {self.seq} in {self.reply_timeout_us} us; error frames "
                                 f"{[P.decode_reply(e) for e in self.errors[-5:]]}, "
                                 f"{len(self.telemetry)} telemetry frames") from None
        assert f.seq == self.seq and f.cmd == P.COMMANDS[name].cmd | P.REPLY_FLAG, f"reply {f} to {name}"
        r = P.decode_reply(f)
        if expect is not None:
            assert r["status"] == expect, f"{name}{fields}: status {P.STATUS_NAME[r['status']]}, " \
                                          f"expected {P.STATUS_NAME[expect]}"
        return r

    async def set(self, axis: int, name: str, value: int, expect: int = P.STATUS["OK"]) -> dict:
        return await self.cmd("SET_PARAM", expect, axis=axis, param=P.PARAMS[name].id, value=value)

    async def get(self, axis: int, name: str) -> int:
        return (await self.cmd("GET_PARAM", axis=axis, param=P.PARAMS[name].id))["value"]

    async def status(self, axis: int) -> dict:
        return await self.cmd("STATUS", axis=axis)

    async def move_encoder(self, axis: int, target: int, step_ns: int = STEP_NS) -> None:
        while self.enc[axis] != target:
            self.enc[axis] += 1 if target > self.enc[axis] else -1
            a, b = QUAD[self.enc[axis] % 4]
            self._set_bit(self.dut.enc_a, axis, a)
            self._set_bit(self.dut.enc_b, axis, b)
            await Timer(step_ns, unit="ns")

    async def move_encoders(self, targets: tuple[int, int], step_ns: int = STEP_NS) -> None:
        """Both axes a count per step toward their targets, one write per pin: two
        move_encoder tasks in the same time step would each write back the other's old bit."""
        while list(self.enc) != list(targets):
            for ax in (0, 1):
                if self.enc[ax] != targets[ax]:
                    self.enc[ax] += 1 if targets[ax] > self.enc[ax] else -1
            (a0, b0), (a1, b1) = QUAD[self.enc[0] % 4], QUAD[self.enc[1] % 4]
            self.dut.enc_a.value = (int(self.dut.enc_a.value) & ~3) | a0 | a1 << 1
            self.dut.enc_b.value = (int(self.dut.enc_b.value) & ~3) | b0 | b1 << 1
            await Timer(step_ns, unit="ns")

    @staticmethod
    def _set_bit(sig, bit: int, v: int) -> None:
        cur = int(sig.value)
        sig.value = (cur & ~(1 << bit)) | (v << bit)

    def pins_high(self) -> int:
        return int(self.dut.rpwm.value) | int(self.dut.lpwm.value)

    async def assert_quiet(self, us: float, what: str) -> None:
        """No bridge PWM pin goes high for ``us`` microseconds."""
        assert self.pins_high() == 0, f"{what}: PWM pin high at start"
        end = now_ns() + us * 1000
        while (left := end - now_ns()) >= 1:
            t = Timer(round(left), unit="ns")     # a fresh timer each time: awaiting one again restarts it
            r = await First(Edge(self.dut.rpwm), Edge(self.dut.lpwm), t)
            if r is t:
                return
            assert self.pins_high() == 0, f"{what}: PWM pin rose (rpwm={self.dut.rpwm.value}, lpwm={self.dut.lpwm.value})"

    async def duty(self, axis: int, pin: str, us: float) -> float:
        """Fraction of ``us`` microseconds that rpwm/lpwm[axis] is high."""
        sig = getattr(self.dut, pin)
        t0 = now_ns()
        end = t0 + us * 1000
        high_since = t0 if (int(sig.value) >> axis) & 1 else None
        high = 0.0
        while True:
            left = end - now_ns()
            t = Timer(round(left), unit="ns") if left >= 1 else None
            r = await First(Edge(sig), t) if t else t
            now = now_ns()
            lvl = (int(sig.value) >> axis) & 1
            if t is None or r is t:
                if high_since is not None:
                    high += end - high_since
                return high / (end - t0)
            if lvl and high_since is None:
                high_since = now
            elif not lvl and high_since is not None:
                high += now - high_since
                high_since = None

    async def fast_pwm(self) -> None:
        await self.set(0, "FDIV", 1, expect=P.STATUS["RANGE"])   # 48.9 kHz: above the bridge's rating
        for ax in (0, 1):
            await self.set(ax, "FDIV", FAST_FDIV)     # 2046-clock PWM period: many periods per test


async def _enable(tb: TB, mask: int = 3) -> None:
    await tb.cmd("ENABLE", mask=mask, enable=1)


@cocotb.test()
async def identify_parameters_and_errors(dut):
    tb = TB(dut)
    await tb.start()
    await tb.assert_quiet(200, "power-up")
    r = await tb.cmd("IDENTIFY")
    assert r["proto_version"] == P.PROTO_VERSION and r["fw_version"] == P.FIRMWARE_VERSION
    assert r["axis_count"] == 2 and r["clk_hz"] == 50_000_000
    # a sample of parameters (all of them: tests/test_firmware_host.py): a random in-range value
    # stored and read back, out of range rejected with nothing changed
    # parameters bounded by others (carrier ceiling, PW0 <= PWMAX, gains that must fit their
    # physical range) have their own checks (firmware host tests); the sample takes the free ones
    bounded = {"FDIV", "PW0", "PWMAX", "PWM_MAX_HZ", "TAU_MAX_MNM", "COUNTS_PER_REV", "KP_Q16", "KD_Q16", "KI_Q16",
               "KD_UNMS_RAD", "KI_UNM_RADS"}
    others = [n for n in P.PARAMS if n not in ("BAUD_DIV", "LAW", "KP_UNM_RAD", "PERIOD_US", "SOFT_MIN") + tuple(bounded)]
    sample = ["LAW", "KP_UNM_RAD", "PERIOD_US", "SOFT_MIN"] + random.sample(others, 3)
    for p in (P.PARAMS[n] for n in sample):
        axes = [P.GLOBAL_AXIS] if p.scope == "global" else [random.randrange(2)]
        for ax in axes:
            v = random.randint(max(p.min, -10**6), min(p.max, 10**6)) if p.name not in ("PERIOD_US",) \
                else random.choice([400, 500, 800])
            if p.name == "SOFT_MIN":
                v = min(v, await tb.get(ax, "SOFT_MAX"))
            if p.name == "SOFT_MAX":
                v = max(v, await tb.get(ax, "SOFT_MIN"))
            got = (await tb.set(ax, p.name, v))["value"]
            if p.name.startswith(("KP_U", "KD_U", "KI_U")):
                tau, cpr = await tb.get(ax, "TAU_MAX_MNM"), await tb.get(ax, "COUNTS_PER_REV")
                raw = P.gain_raw_from_phys(v, tau, cpr)
                assert got == P.gain_phys_from_raw(raw, tau, cpr), f"{p.name} {v} -> {got}"
                assert await tb.get(ax, p.name.split("_")[0] + "_Q16") == raw
            else:
                assert got == v and await tb.get(ax, p.name) == v, f"{p.name}[{ax}] = {v}, read {got}"
            before = await tb.get(ax, p.name)
            if p.max < 0x7FFF_FFFF:
                await tb.set(ax, p.name, p.max + 1, expect=P.STATUS["RANGE"])
            if p.min > -0x7FFF_FFFF:
                await tb.set(ax, p.name, p.min - 1, expect=P.STATUS["RANGE"])
            assert await tb.get(ax, p.name) == before
    # wrong scope, unknown parameter, unknown command, wrong payload length
    await tb.cmd("GET_PARAM", P.STATUS["BAD_ARG"], axis=0, param=P.PARAMS["PERIOD_US"].id)
    await tb.cmd("GET_PARAM", P.STATUS["BAD_ARG"], axis=2, param=P.PARAMS["LAW"].id)
    await tb.cmd("GET_PARAM", P.STATUS["BAD_ARG"], axis=0, param=99)
    tb.seq += 1
    await tb.send_raw(P.encode_frame(tb.seq, 0x55, b""))
    f = await with_timeout(tb.replies.get(), 2000, "us")
    assert P.decode_reply(f)["status"] == P.STATUS["UNKNOWN_CMD"]
    tb.seq += 1
    await tb.send_raw(P.encode_frame(tb.seq, P.COMMANDS["STOP"].cmd, b"\x01\x02"))
    f = await with_timeout(tb.replies.get(), 2000, "us")
    assert P.decode_reply(f)["status"] == P.STATUS["LENGTH"]
    await tb.cmd("BOOTLOADER", P.STATUS["BAD_ARG"], magic=0x1234)
    c = await tb.cmd("COUNTERS")
    assert c["unknown"] == 1 and c["length"] == 1 and c["frames_ok"] > 20
    await tb.assert_quiet(100, "after parameter traffic")


@cocotb.test()
async def each_law_drives_both_axes_as_the_reference(dut):
    tb = TB(dut)
    await tb.start()
    await tb.fast_pwm()
    await tb.cmd("MOVE", P.STATUS["STATE"], axis=0, mode=U, target=100)   # disabled: refused
    for ax in (0, 1):
        await tb.set(ax, "KP_Q16", 65536 * 2)        # 2 PWM steps per count
        await tb.set(ax, "KD_Q16", 655)              # 0.01 step per count/s
        await tb.set(ax, "KI_Q16", 65536 * 20)       # 20 steps per count*s (about 62 N m/(rad s), under the 100 maximum)
        await tb.set(ax, "FOLLOW_LIMIT", 100000)
    await _enable(tb)
    for law_name, law in (("P", 1), ("PD", 2), ("PID", 3)):
        for ax in (0, 1):
            await tb.set(ax, "LAW", law)
            await tb.cmd("STOP", mask=1 << ax)
            pos = tb.enc[ax]
            target = pos + random.choice([-1, 1]) * random.randint(60, 200)
            await tb.cmd("MOVE", P.STATUS["NOT_HOMED"], axis=ax, mode=0, target=target)
            await tb.cmd("MOVE", axis=ax, mode=U, target=target)
            await Timer(3 * PERIOD_US, unit="us")
            st = await tb.status(ax)
            e = target - pos
            assert st["setpoint"] == target and st["position"] == pos
            if law != 3:
                assert st["pwm_cmd"] == ref.clamp(ref.round_q16(2 * 65536 * e), 1023), \
                    f"{law_name} axis {ax}: cmd {st['pwm_cmd']} for error {e}: {st}"
            else:
                assert abs(st["pwm_cmd"]) > abs(2 * e), f"PID integrates: cmd {st['pwm_cmd']} error {e}"
            # the sign and magnitude reach the pins: the side named by the error's sign switches
            side, other = ("rpwm", "lpwm") if st["pwm_cmd"] > 0 else ("lpwm", "rpwm")
            d = await tb.duty(ax, side, 3 * PWM_PERIOD_US)
            expect = min(1023, abs(st["pwm_cmd"])) / 1023
            if law != 3:
                assert abs(d - expect) < 0.03, f"{law_name} axis {ax}: duty {d:.3f}, expected {expect:.3f}"
            else:
                assert d > 0.05
            assert await tb.duty(ax, other, PWM_PERIOD_US) == 0.0
            # PD: the D term uses the measured velocity (encoder moving toward the target)
            if law == 2:
                mover = cocotb.start_soon(tb.move_encoder(ax, pos + (120 if e > 0 else -120), step_ns=10_000))
                await Timer(800, unit="us")
                st2 = await tb.status(ax)
                v = st2["velocity_q8"] / 256
                assert 90_000 < abs(v) < 110_000 and (v > 0) == (e > 0), f"velocity {v} counts/s, driven at 100000: {st2}"
                # STATUS holds the last iteration's position, velocity and command: recompute it
                e2 = (st2["setpoint"] - st2["position"]) << 16
                u = ((2 * 65536 * e2) >> 16) - ((655 * st2["velocity_q8"]) >> 8)
                assert st2["pwm_cmd"] == ref.clamp(ref.round_q16(u), 1023), f"PD command: {st2}"
                assert (st2["pwm_cmd"] - ref.round_q16(2 * e2)) * v < 0, "the D term opposes the motion"
                await mover
    st = await tb.status(0)
    cocotb.log.info(f"worst control iteration {st['loop_cycles_max']} cycles, "
                    f"worst interrupt lateness {st['jitter_cycles_max']} cycles")
    await tb.cmd("ENABLE", mask=3, enable=0)
    await tb.assert_quiet(50, "disabled")


@cocotb.test()
async def link_watchdog_stops_a_silent_link(dut):
    tb = TB(dut)
    await tb.start()
    await tb.fast_pwm()
    await tb.set(P.GLOBAL_AXIS, "LINK_TIMEOUT_MS", 10)
    await _enable(tb, 1)
    await tb.cmd("MOVE", axis=0, mode=U, target=300)
    t_last_cmd = now_ns() / 1000               # the last command that shows the host in control
    await Timer(2 * PERIOD_US, unit="us")     # next iteration, next PWM period
    assert await tb.duty(0, "rpwm", 2 * PWM_PERIOD_US) > 0.03     # Table 1 P gain: 78 of 1023 steps
    # a monitor that only polls (fresh seqs) and identifies does not keep the axis running
    t0 = now_ns() / 1000
    polls = 0
    while tb.pins_high() or (await tb.duty(0, "rpwm", PWM_PERIOD_US)) > 0:
        await tb.status(0)
        await tb.cmd("IDENTIFY")
        polls += 1
        assert now_ns() / 1000 - t0 < 15_000, "no stop after 15 ms without a control command"
    stopped = now_ns() / 1000 - t_last_cmd
    assert polls > 5 and 9_900 < stopped < 12_000, \
        f"stopped {stopped} us after the last control command ({polls} polls since), the timeout is 10 ms"
    st = await tb.status(0)
    assert st["faults"] == P.FAULT["LINK"] and not st["enabled"]
    await tb.assert_quiet(200, "after the link fault")
    await tb.cmd("ENABLE", P.STATUS["STATE"], mask=1, enable=1)
    await tb.cmd("CLEAR_FAULT", mask=1)
    await _enable(tb, 1)                     # set-point = present position: no jump
    assert (await tb.status(0))["setpoint"] == 0
    await tb.assert_quiet(100, "re-enabled at its own position")
    # HEARTBEATs keep it enabled for twice the timeout
    t0 = now_ns() / 1000
    while now_ns() / 1000 - t0 < 20_000:
        await tb.cmd("HEARTBEAT")
        await Timer(3_000, unit="us")
    st = await tb.status(0)
    assert st["enabled"] and st["faults"] == 0, st


@cocotb.test()
async def estop_bridge_fault_following_soft_limit_and_encoder_faults(dut):
    tb = TB(dut)
    await tb.start()
    await tb.fast_pwm()

    async def running(ax: int, target: int) -> None:
        await _enable(tb, 1 << ax)
        await tb.cmd("MOVE", axis=ax, mode=U, target=target)
        await Timer(2 * PERIOD_US, unit="us")
        assert await tb.duty(ax, "rpwm" if target > tb.enc[ax] else "lpwm", 2 * PWM_PERIOD_US) > 0.02

    async def faulted(ax: int, fault: str) -> None:
        await tb.assert_quiet(100, fault)
        st = await tb.status(ax)
        assert st["faults"] & P.FAULT[fault] and not st["enabled"], f"{fault}: {st}"

    # e-stop (KEY0): pins low within the clock, fault latched, clear refused while pressed
    await running(0, 200)
    dut.estop.value = 1
    await Timer(1, unit="ns")
    assert tb.pins_high() == 0, "e-stop must drop the PWM pins combinationally"
    await Timer(2 * PERIOD_US, unit="us")
    await faulted(0, "ESTOP")
    await tb.cmd("CLEAR_FAULT", P.STATUS["STATE"], mask=3)
    await tb.cmd("ENABLE", P.STATUS["STATE"], mask=1, enable=1)
    dut.estop.value = 0
    await Timer(10, unit="us")
    await tb.assert_quiet(2 * PERIOD_US, "e-stop released, fault still latched")
    await tb.cmd("CLEAR_FAULT", mask=3)

    # bridge fault of axis 1
    await running(1, -150)
    TB._set_bit(dut.bridge_fault, 1, 1)
    await Timer(2 * PERIOD_US, unit="us")
    await faulted(1, "BRIDGE")
    await tb.cmd("CLEAR_FAULT", P.STATUS["STATE"], mask=2)
    TB._set_bit(dut.bridge_fault, 1, 0)
    await Timer(10, unit="us")
    await tb.cmd("CLEAR_FAULT", mask=2)

    # following error: a step larger than the limit is refused up front; an axis
    # pushed away from its set-point beyond the limit trips
    await tb.set(0, "FOLLOW_LIMIT", 50)
    await _enable(tb, 1)
    await tb.cmd("MOVE", P.STATUS["RANGE"], axis=0, mode=U, target=60)
    await tb.move_encoder(0, -51)
    await Timer(2 * PERIOD_US, unit="us")
    await faulted(0, "FOLLOWING")
    await tb.move_encoder(0, 0)
    await tb.cmd("CLEAR_FAULT", mask=1)
    await tb.set(0, "FOLLOW_LIMIT", 16800)

    # soft limits: a target outside is refused; a position outside trips the axis
    await tb.set(0, "SOFT_MAX", 20)
    await _enable(tb, 1)
    await tb.cmd("MOVE", P.STATUS["RANGE"], axis=0, mode=U, target=21)
    await tb.move_encoder(0, 25)
    await Timer(2 * PERIOD_US, unit="us")
    await faulted(0, "SOFT_LIMIT")
    await tb.cmd("CLEAR_FAULT", mask=1)
    await tb.move_encoder(0, 0)
    await tb.set(0, "SOFT_MAX", 1_000_000)

    # illegal encoder transition (A and B change together)
    await _enable(tb, 2)
    dut.enc_a.value = int(dut.enc_a.value) ^ 2
    dut.enc_b.value = int(dut.enc_b.value) ^ 2
    await Timer(2 * PERIOD_US, unit="us")
    await faulted(1, "ENCODER")
    dut.enc_a.value = int(dut.enc_a.value) ^ 2
    dut.enc_b.value = int(dut.enc_b.value) ^ 2
    await Timer(20, unit="us")
    await tb.cmd("CLEAR_FAULT", mask=2)
    await _enable(tb, 2)
    assert (await tb.status(1))["faults"] == 0


@cocotb.test()
async def runaway_with_a_frozen_and_a_reversed_encoder(dut):
    """Encoder loss at the pins: a step the encoder never follows (frozen), then
    one it follows the wrong way (reversed wiring), each stops the bridge pins
    and latches RUNAWAY.  Frozen: the runaway check, STALL_MS plus a period or
    two after the move (the plausibility check's lower bound needs far longer to
    build up ENC_SLACK counts).  Reversed: the encoder counts only once the
    bridge drives (a motor at rest moves when driven), and the plausibility
    check trips once it is ENC_SLACK counts behind - long before STALL_MS,
    whatever the core's speed (docs/safety.md)."""
    tb = TB(dut)
    await tb.start()
    await tb.fast_pwm()
    stall_ms = 20
    step_us = 20                                    # the reversed encoder: 50 000 counts/s
    await tb.set(0, "STALL_MS", stall_ms)
    await tb.set(P.GLOBAL_AXIS, "LINK_TIMEOUT_MS", 1000)
    await tb.set(0, "KP_Q16", 65536)                # 1 step per count: 300 counts -> 300 >= STALL_CMD
    await tb.set(0, "LAW", 1)
    slack = await tb.get(0, "ENC_SLACK")

    async def reversed_once_driven() -> None:
        while not int(dut.rpwm.value) & 1:          # axis 0 driven toward the target
            await Edge(dut.rpwm)
        await tb.move_encoder(0, tb.enc[0] - 2000, step_ns=step_us * 1000)

    for kind in ("frozen", "reversed"):
        await _enable(tb, 1)
        mover = cocotb.start_soon(reversed_once_driven()) if kind == "reversed" else None
        target = tb.enc[0] + 300
        await tb.cmd("MOVE", axis=0, mode=U, target=target)
        t_move = now_ns() / 1000
        await Timer(2 * PERIOD_US, unit="us")
        if kind == "frozen":   # reversed: the encoder moves only once driven, and trips within the bound below
            assert await tb.duty(0, "rpwm", 2 * PWM_PERIOD_US) > 0.1, f"{kind}: not driving toward the target"
        while tb.pins_high() or (await tb.duty(0, "rpwm", PWM_PERIOD_US)) > 0:
            await Timer(100, unit="us")
            assert now_ns() / 1000 - t_move < 3 * stall_ms * 1000, f"{kind} encoder: still driving"
        tripped = now_ns() / 1000 - t_move
        if mover is not None:
            mover.kill()
        st = await tb.status(0)
        cocotb.log.info(f"{kind} encoder: pins off {tripped:.0f} us after the move (STALL_MS {stall_ms} ms, "
                        f"ENC_SLACK {slack} counts)")
        assert st["faults"] == P.FAULT["RUNAWAY"] and not st["enabled"], st
        if kind == "frozen":
            assert stall_ms * 1000 <= tripped <= stall_ms * 1000 + 4 * PERIOD_US, f"{kind}: {tripped} us"
        else:   # ENC_SLACK counts the wrong way, then the check's period and the one that references it
            assert slack * step_us <= tripped <= slack * step_us + 4 * PERIOD_US, f"{kind}: {tripped} us"
        await tb.assert_quiet(200, f"after RUNAWAY ({kind})")
        await tb.cmd("CLEAR_FAULT", mask=1)


@cocotb.test()
async def overruns_counted_when_a_period_is_missed(dut):
    """STATUS.overruns stays 0 through a normal run (both axes PID on trapezoids,
    encoders counting, the link busy with authenticated STATUS commands), then
    counts each missed period: the SoC timer's mtime is moved 3 periods ahead in
    one clock, as a CPU held that long would find it (no legal PERIOD_US is
    shorter than the iteration on either core: docs/firmware.md, "Timing").
    Each jump is one overrun; the loop goes on at its period, no fault."""
    tb = TB(dut)
    tb.reply_timeout_us = 50_000
    await tb.start()
    await tb.fast_pwm()
    await tb.set(P.GLOBAL_AXIS, "LINK_TIMEOUT_MS", 1000)
    for ax in (0, 1):
        await tb.set(ax, "LAW", 3)
        await tb.set(ax, "KD_Q16", 655)
        await tb.set(ax, "KI_Q16", 65536 * 20)
        await tb.set(ax, "FOLLOW_LIMIT", 1_000_000)
    await _enable(tb)

    mover = cocotb.start_soon(tb.move_encoders((tb.enc[0] - 200, tb.enc[1] + 200), step_ns=8_000))
    for ax in (0, 1):
        await tb.cmd("MOVE", axis=ax, mode=U | P.MOVE_TRAPEZOID, target=tb.enc[ax] + 100 * (1 if ax else -1))
    while not mover.done():
        await tb.status(0)
    st = await tb.status(0)
    cocotb.log.info(f"normal run: worst iteration {st['loop_cycles_max']} cycles, lateness "
                    f"{st['jitter_cycles_max']}, overruns {st['overruns']}")
    assert st["overruns"] == 0 and st["faults"] == 0 and st["enabled"], st

    period = PERIOD_US * 1000 // CLK_NS
    mtime = dut.u_fabric.u_timer.mtime_q
    jumps = 3
    for _ in range(jumps):
        mtime.value = int(mtime.value) + 3 * period
        await Timer(5 * PERIOD_US, unit="us")
    st = await tb.status(1)
    cocotb.log.info(f"after {jumps} missed periods: overruns {st['overruns']}")
    assert st["overruns"] == jumps and st["faults"] == 0 and st["enabled"], st
    await Timer(4 * PERIOD_US, unit="us")
    st = await tb.status(0)
    assert st["overruns"] == jumps and st["faults"] == 0, f"overruns counted at a period the iteration fits: {st}"


@cocotb.test()
async def lengthening_the_period_with_frames_queued_keeps_the_watchdog_fed(dut):
    """Lengthening PERIOD_US with frames queued behind it could trip the
    watchdog (the firmware reloaded it with 4 old periods while the next tick was a
    new period away).  The hardware watchdog is now the boot ROM's, fixed, and fed
    by every tick: 0.5 ms -> 25 ms with 20 frames queued latches nothing, and an
    axis enabled through it keeps driving."""
    tb = TB(dut)
    await tb.start()
    await tb.fast_pwm()
    await tb.set(P.GLOBAL_AXIS, "LINK_TIMEOUT_MS", 1000)
    await _enable(tb, 1)
    await tb.cmd("MOVE", axis=0, mode=U, target=300)
    tb.seq += 1
    burst = P.request("SET_PARAM", tb.seq, axis=P.GLOBAL_AXIS, param=P.PARAMS["PERIOD_US"].id, value=25_000)
    for _ in range(20):                       # queued behind it: the main loop is busy for a while
        tb.seq += 1
        burst += P.request("STATUS", tb.seq, axis=0)
    tb.reply_timeout_us = 20_000
    await tb.send_raw(burst)
    await Timer(120_000, unit="us")           # several new periods, beyond the old 4-period watchdog
    tb.replies = type(tb.replies)()           # drop the burst's replies
    st = await tb.status(0)
    assert st["faults"] == 0 and st["enabled"], st
    assert not st["safety"] & 0x01, f"the SoC latch forced the drives safe: {st}"
    assert await tb.duty(0, "rpwm", 2 * PWM_PERIOD_US) > 0.03, "axis 0 no longer drives"
    await tb.set(P.GLOBAL_AXIS, "PERIOD_US", PERIOD_US)


@cocotb.test()
async def corrupted_random_and_replayed_frames_change_nothing(dut):
    tb = TB(dut)
    await tb.start()
    await tb.fast_pwm()
    await _enable(tb, 1)                      # axis 0 holds at 0, axis 1 disabled
    await tb.set(0, "KP_Q16", 70000)
    old_frame = tb.sent[-1]                   # a recorded authenticated SET_PARAM
    await tb.set(0, "KP_Q16", 80000)
    names = [(ax, p.name) for p in P.PARAMS.values() for ax in ([P.GLOBAL_AXIS] if p.scope == "global" else [0, 1])]
    before = {k: await tb.get(*k) for k in names}
    c0 = await tb.cmd("COUNTERS")
    # commands that would move or reconfigure if any got through
    templates = [P.request("MOVE", 0, axis=0, mode=U, target=5000),
                 P.request("ENABLE", 0, mask=3, enable=1),
                 P.request("SET_PARAM", 0, axis=0, param=P.PARAMS["KP_Q16"].id, value=1),
                 P.request("SET_PARAM", 0, axis=P.GLOBAL_AXIS, param=P.PARAMS["PERIOD_US"].id, value=300)]
    stream = bytearray()
    sent = {"corrupt": 0, "random": 0, "truncated": 0, "oversize": 0, "replay": 0, "hello": 0}
    for _ in range(60):
        kind = random.choice(list(sent))
        if kind == "corrupt":
            fr = bytearray(random.choice(templates)[:-1])
            for _ in range(random.randint(1, 3)):
                i = random.randrange(len(fr))
                fr[i] ^= 1 << random.randrange(8)
            chunk = bytes(fr)
        elif kind == "random":
            chunk = bytes(random.randrange(256) for _ in range(random.randint(1, 40)))
        elif kind == "truncated":
            fr = random.choice(templates)
            chunk = fr[:random.randint(2, len(fr) - 2)]
        elif kind == "oversize":
            chunk = bytes(random.randrange(1, 256) for _ in range(random.randint(P.MAX_ENCODED + 1, 120)))
        elif kind == "replay":
            chunk = old_frame[:-1]
        else:
            chunk = b"*HELLO*"
        # skip the (2^-16) corruption that is itself a valid new command - that is not a firmware failure
        for part in chunk.split(b"\x00"):
            r = P.parse_packet(part) if part else None
            if isinstance(r, P.Frame) and kind != "replay":
                break
        else:
            sent[kind] += 1
            stream += chunk + b"\x00"
    cocotb.log.info(f"flood: {len(stream)} bytes, {sent}")
    quiet = cocotb.start_soon(tb.assert_quiet(len(stream) * 10 + 2000, "flood"))
    await tb.send_raw(bytes(stream))
    await quiet
    replayed = []
    while not tb.replies.empty():          # the replays' REPLAY answers
        replayed.append(P.decode_reply(tb.replies.get_nowait())["status"])
    assert replayed == [P.STATUS["REPLAY"]] * sent["replay"], replayed
    after = {k: await tb.get(*k) for k in names}
    assert after == before, {k: (before[k], after[k]) for k in names if before[k] != after[k]}
    st0, st1 = await tb.status(0), await tb.status(1)
    assert st0["enabled"] and st0["setpoint"] == 0 and not st1["enabled"]
    c1 = await tb.cmd("COUNTERS")
    bad = sum(c1[k] - c0[k] for k in ("crc", "framing", "length", "oversize", "unknown", "replay"))
    assert bad >= sum(sent.values()) - sent["random"], f"errors counted {bad}, sent {sent}"
    assert c1["replay"] - c0["replay"] == sent["replay"]
    assert len(tb.errors) > 0


@cocotb.test()
async def telemetry_trapezoid_and_bootloader_jump(dut):
    tb = TB(dut)
    await tb.start()
    await tb.fast_pwm()
    await tb.set(0, "VMAX", 40_000)
    await tb.set(0, "AMAX", 20_000_000)
    await tb.set(0, "FOLLOW_LIMIT", 1_000_000)
    await _enable(tb, 1)
    # the MOVE first: its MAC check (~0.6 ms of the main loop) while records fall due every 1 ms
    # could send one a period late (docs/security.md, 'Costs'); TELEMETRY itself needs no MAC
    await tb.cmd("MOVE", axis=0, mode=U | P.MOVE_TRAPEZOID, target=400)
    await tb.cmd("TELEMETRY", every=2)
    await Timer(14_000, unit="us")
    await tb.cmd("TELEMETRY", every=0)
    await Timer(2 * PERIOD_US, unit="us")
    n = len(tb.telemetry)
    await Timer(4 * PERIOD_US, unit="us")
    assert len(tb.telemetry) == n, "telemetry must stop"
    t = [r["time_us"] for _, r in tb.telemetry]
    assert all(b - a == 2 * PERIOD_US for a, b in zip(t, t[1:])), f"telemetry times {t}"
    sp = [r["axes"][0]["setpoint"] for _, r in tb.telemetry]
    dsp = [b - a for a, b in zip(sp, sp[1:])]
    vmax_per_2T = 40_000 * 2 * PERIOD_US / 1e6
    assert sp[-1] == 400 and all(0 <= d <= vmax_per_2T + 1 for d in dsp), f"set-points {sp}"
    assert max(dsp) >= vmax_per_2T - 1, "the profile reaches its top speed"
    # bootloader hook: refused with a bad magic, then drives off, reply, restart from the boot ROM
    await tb.cmd("BOOTLOADER", magic=P.BOOTLOADER_MAGIC)
    await Timer(2 * PERIOD_US + 1500, unit="us")     # restart: the key's setup, then the first periods
    r = await tb.cmd("IDENTIFY")
    assert r["last_seq"] == 0, "the image restarted through the boot ROM (fresh sequence state)"
    st = await tb.status(0)
    assert not st["enabled"] and st["loop_cycles_max"] > 0
    await tb.assert_quiet(100, "after the bootloader jump")


@cocotb.test()
async def authentication_at_the_pins(dut):
    """Who may drive the pins (docs/security.md): without the key nothing that
    changes the machine runs and the pins stay quiet; with it the same
    commands drive them; a recorded authenticated frame replayed - also after
    the link's seq was walked round by frames without the key - is refused;
    STOP and disable need no key."""
    tb = TB(dut)
    await tb.start()
    await tb.fast_pwm()
    kp = await tb.get(0, "KP_Q16")
    for name, fields in (("SET_PARAM", dict(axis=0, param=P.PARAMS["KP_Q16"].id, value=5)),
                         ("SET_PARAM", dict(axis=P.GLOBAL_AXIS, param=P.PARAMS["LINK_TIMEOUT_MS"].id, value=60_000)),
                         ("ENABLE", dict(mask=3, enable=1)), ("MOVE", dict(axis=0, mode=U, target=500)),
                         ("CLEAR_FAULT", dict(mask=3)), ("BOOTLOADER", dict(magic=P.BOOTLOADER_MAGIC))):
        await tb.cmd(name, P.STATUS["AUTH"], tagged=False, **fields)
    # a MAC of another key
    wrong = auth.Session(bytes(32), tb.sess.host_nonce, tb.sess.board_nonce)
    tb.seq += 1
    await tb.send_raw(wrong.request("ENABLE", tb.seq, mask=1, enable=1))
    f = await with_timeout(tb.replies.get(), 2000, "us")
    assert P.decode_reply(f)["status"] == P.STATUS["AUTH"]
    await tb.assert_quiet(3 * PERIOD_US, "commands without the key")
    assert await tb.get(0, "KP_Q16") == kp
    assert not (await tb.status(0))["enabled"] and not (await tb.status(1))["enabled"]
    assert (await tb.cmd("COUNTERS"))["auth"] == 7
    # with the key: the same commands drive the pins
    await _enable(tb, 1)
    await tb.cmd("MOVE", axis=0, mode=U, target=300)
    move = tb.sent[-1]
    await Timer(2 * PERIOD_US, unit="us")
    assert await tb.duty(0, "rpwm", 41) > 0.03
    await tb.cmd("MOVE", axis=0, mode=U, target=0)
    await Timer(2 * PERIOD_US, unit="us")
    assert (await tb.status(0))["pwm_cmd"] == 0
    # the recorded MOVE again: refused ...
    await tb.send_raw(move)
    f = await with_timeout(tb.replies.get(), 2000, "us")
    assert P.decode_reply(f)["status"] == P.STATUS["REPLAY"]
    # ... also once frames without the key have walked the link's seq round
    old = P.parse_packet(move.strip(b"\0")).seq
    for k in (1, 2, 3):
        tb.seq = (old + k * 0x4000) & 0xFFFF
        await tb.send_raw(P.request("STATUS", tb.seq, axis=0))
        await with_timeout(tb.replies.get(), 2000, "us")
    await tb.send_raw(move)
    f = await with_timeout(tb.replies.get(), 2000, "us")
    assert P.decode_reply(f)["status"] == P.STATUS["REPLAY"]
    await tb.cmd("MOVE", P.STATUS["NO_SESSION"], axis=0, mode=U, target=300)   # seq outside the session now
    await tb.open_session()                                                    # what the host tool does then
    await Timer(2 * PERIOD_US, unit="us")
    st = await tb.status(0)
    assert st["setpoint"] == 0 and st["pwm_cmd"] == 0, f"a replayed MOVE ran: {st}"
    # stopping needs no key
    await tb.cmd("MOVE", axis=0, mode=U, target=300)
    await Timer(2 * PERIOD_US, unit="us")
    assert await tb.duty(0, "rpwm", 41) > 0.03
    await tb.cmd("STOP", tagged=False, mask=1)
    await Timer(2 * PERIOD_US, unit="us")
    assert (await tb.status(0))["setpoint"] == 0
    await tb.cmd("MOVE", axis=0, mode=U, target=300)
    await tb.cmd("ENABLE", tagged=False, mask=3, enable=0)
    await tb.assert_quiet(3 * PERIOD_US, "disabled without the key")


@cocotb.test()
async def no_key_board_refuses_motion(dut):
    """The same image with the stub ROM's key slot blank (written into the
    model's ROM before reset, put back after): a board without a key says
    NO_KEY to a session and to motion, even with a MAC, and its pins stay
    quiet; reading and disabling work."""
    rom = dut.u_fabric.u_rom.mem
    with_key, blank = firmware.rom_words(KEY), firmware.rom_words(None)
    slot = [i for i, (a, b) in enumerate(zip(with_key, blank)) if a != b]
    assert slot and [int(rom[i].value) for i in slot] == [with_key[i] for i in slot], "the ROM holds the test key"
    for i in slot:
        rom[i].value = blank[i]
    try:
        tb = TB(dut)
        await tb.start(session=False)
        await tb.open_session(P.STATUS["NO_KEY"])
        await tb.cmd("ENABLE", P.STATUS["NO_KEY"], tagged=False, mask=1, enable=1)
        tb.sess = auth.Session(KEY, bytes(16), bytes(16))
        await tb.cmd("ENABLE", P.STATUS["NO_KEY"], mask=1, enable=1)
        await tb.cmd("MOVE", P.STATUS["NO_KEY"], axis=0, mode=U, target=500)
        await tb.cmd("ENABLE", tagged=False, mask=3, enable=0)
        await tb.assert_quiet(3 * PERIOD_US, "a board without a key")
        assert not (await tb.status(0))["enabled"]
    finally:
        for i in slot:
            rom[i].value = with_key[i]


#: The bench in parts that share one build and simulate at once (pytest-xdist
#: puts them on both cores), of about equal length.  A test named in no part
#: runs in the last; the measurements (skipped unless a benchmark asks) in none:
#: a test named in cocotb's filter runs even when marked skip.
PARTS: dict[str, list[str]] = {
    "watchdog": ["lengthening_the_period_with_frames_queued_keeps_the_watchdog_fed"],
    "runaway": ["runaway_with_a_frozen_and_a_reversed_encoder", "overruns_counted_when_a_period_is_missed"],
    "link": ["link_watchdog_stops_a_silent_link"],
    "faults": ["estop_bridge_fault_following_soft_limit_and_encoder_faults", "each_law_drives_both_axes_as_the_reference"],
    "frames": ["corrupted_random_and_replayed_frames_change_nothing", "telemetry_trapezoid_and_bootloader_jump"],
}


def _part(name: str) -> list[str]:
    if name != "rest":
        return PARTS[name]
    kind = type(no_key_board_refuses_motion)      # what @cocotb.test() makes of a function
    named = {t for ts in PARTS.values() for t in ts}
    return [n for n, v in globals().items() if type(v) is kind and n not in named and not v.skip]


@pytest.mark.parametrize("part", [*PARTS, "rest"])
@pytest.mark.parametrize("sim", ["verilator"])
def test_firmware(sim, part):
    from torqueloop.flow.simrun import run, sims_for
    if sim not in sims_for("soc"):
        pytest.skip(f"{sim} not selected")
    img = servo_tb_image()
    run("soc", sim, "test_firmware", parameters={"RAM_INIT": f'"{img.ram_hex}"', "ROM_INIT": f'"{img.rom_hex}"'},
        testcase=_part(part))


@cocotb.test(skip=os.environ.get("TL_FW_MEASURE") != "1")
async def measure_control_iteration(dut):
    """Benchmark (scripts/benches/bench_firmware.py): worst-case load - both axes PID with
    trapezoid moves (TL_FW_MOVE_MODE=0: steps; TL_FW_SHORT_MOVE=1: a short trapezoid that
    brakes inside the window), edge-timestamp velocity, both encoders
    counting, telemetry streaming, link traffic - at the period TL_FW_PERIOD_US; writes
    the worst iteration cycles and lateness to JSON."""
    tb = TB(dut)
    # replies queue behind telemetry on a busy link, and a MAC check (~29 000 cycles) gets
    # only what the control interrupt leaves of the CPU: at 20 kHz a few ms
    tb.reply_timeout_us = 50_000
    await tb.start()
    await tb.fast_pwm()
    period = int(os.environ.get("TL_FW_PERIOD_US", "200"))
    await tb.set(P.GLOBAL_AXIS, "PERIOD_US", period)
    for ax in (0, 1):
        await tb.set(ax, "LAW", 3)
        await tb.set(ax, "KD_Q16", 655)
        await tb.set(ax, "KI_Q16", 65536 * 20)
        await tb.set(ax, "FOLLOW_LIMIT", 1_000_000)
        for name in ("KVFF_Q16", "KAFF_Q16"):   # the feed-forwards (off unless the bench asks)
            if int(os.environ.get(f"TL_FW_{name}", "0")):
                await tb.set(ax, name, int(os.environ[f"TL_FW_{name}"]))
    await _enable(tb)
    # a 50-byte telemetry frame takes 500 us at 1 Mbaud: one every 800 us keeps up
    await tb.cmd("TELEMETRY", every=-(-800 // period))
    mode = int(os.environ.get("TL_FW_MOVE_MODE", "1"))
    target = 2000
    if os.environ.get("TL_FW_SHORT_MOVE") == "1":
        # a trapezoid that accelerates (1 ms), cruises and brakes (1 ms) inside the window:
        # the braking samples are the profile's dearest (the braking speed's search and divide)
        target = 60
        for ax in (0, 1):
            await tb.set(ax, "VMAX", 50_000)
            await tb.set(ax, "AMAX", 50_000_000)
    movers = [cocotb.start_soon(tb.move_encoders((-300, 300), step_ns=8_000))]
    for ax in (0, 1):
        await tb.cmd("MOVE", axis=ax, mode=U | mode, target=target * (1 if ax else -1))
    n_cmd = 0
    t_end = now_ns() + 3_000_000
    while now_ns() < t_end:
        await tb.status(n_cmd % 2)
        n_cmd += 1
    for m in movers:
        await m
    st = [await tb.status(ax) for ax in (0, 1)]
    await tb.cmd("TELEMETRY", every=0)
    c = await tb.cmd("COUNTERS")
    out = {"period_us": period, "move_mode": mode, "target": target, "loop_cycles_max": st[0]["loop_cycles_max"],
           "jitter_cycles_max": st[0]["jitter_cycles_max"], "commands_answered": n_cmd,
           "telemetry_frames": len(tb.telemetry), "telemetry_dropped": c["tx_dropped"],
           "faults": [s["faults"] for s in st]}
    cocotb.log.info(f"measurement: {out}")
    Path(os.environ.get("TL_FW_MEASURE_OUT", "fw_measure.json")).write_text(json.dumps(out))
    assert out["faults"] == [0, 0] and out["loop_cycles_max"] < period * 50
    assert [s["position"] for s in st] == [-300, 300], f"both encoders counted: {st}"


@cocotb.test(skip=os.environ.get("TL_AUTH_MEASURE") != "1")
async def measure_authentication(dut):
    """Benchmark (scripts/benches/bench_auth.py): what a MAC costs the running
    firmware.  The same STOP with and without its MAC, and a SESSION: time
    from the request's last stop bit to the reply's last byte, the fastest of
    REPEAT (a control iteration or telemetry may delay any one of them); the
    difference of the two STOPs is the check of one authenticated frame
    (its 16 more bytes are already received when the clock starts).  Axis 0
    runs P control on a held position meanwhile; writes JSON."""
    tb = TB(dut)
    await tb.start()
    await _enable(tb, 1)
    repeat = int(os.environ.get("TL_AUTH_REPEAT", "12"))

    async def timed(name: str, tagged: bool, **fields) -> float:
        best = float("inf")
        for _ in range(repeat):
            tb.seq = (tb.seq + 1) & 0xFFFF
            wire = tb.sess.request(name, tb.seq, **fields) if tagged else P.request(name, tb.seq, **fields)
            await tb.send_raw(wire)
            t0 = now_ns()
            f = await with_timeout(tb.replies.get(), 20_000, "us")
            assert P.decode_reply(f)["status"] == P.STATUS["OK"], P.decode_reply(f)
            best = min(best, tb.reply_ns - t0)
            await Timer(random.randrange(50, 300), unit="us")
        return best / CLK_NS

    plain = await timed("STOP", False, mask=1)
    tagged = await timed("STOP", True, mask=1)
    session = await timed("SESSION", False, host_nonce=bytes(16))
    st = await tb.status(0)
    out = {"stop_cycles": plain, "stop_authenticated_cycles": tagged, "session_cycles": session,
           "frame_auth_cycles": tagged - plain, "loop_cycles_max": st["loop_cycles_max"],
           "jitter_cycles_max": st["jitter_cycles_max"], "period_us": PERIOD_US, "faults": st["faults"]}
    cocotb.log.info(f"authentication: {out}")
    Path(os.environ.get("TL_AUTH_MEASURE_OUT", "auth_measure.json")).write_text(json.dumps(out))
    assert st["faults"] == 0 and tagged > plain
