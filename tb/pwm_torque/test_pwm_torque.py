# SPDX-License-Identifier: MIT
"""pwm_torque: period and duty measured on the bridge pins for divisor/duty
pairs (0, dead zone, mid, full scale), direction change only at a period
boundary, fault/enable response within one clock and resumption only at a
period start, both bridge modes, and a seeded random stream compared with
the reference model every clock.

The tick is made here (the test's own divider, a tick every `div` clocks),
so the pins' period must be div * (2^PWM_BITS - 1) clocks and the high time
map_duty(...) * div clocks.
"""

import random
from dataclasses import asdict

import cocotb
import pytest
from cocotb.clock import Clock
from cocotb.triggers import FallingEdge, ReadOnly, RisingEdge, Timer

from torqueloop.flow.manifest import REPO_ROOT
from torqueloop.oracles.freq_div import FreqDivParams, carrier_hz, count_max
from torqueloop.oracles.pwm_torque import (PIPE_CLOCKS, PwmInputs, PwmOutputs, PwmTorqueModel,
                                       full_scale, map_duty, safe_pins)
from torqueloop.flow.simrun import run, sims_for

import tbutil

PINS = PwmOutputs.PINS
STATUS = ("period_start", "duty_applied", "dir_applied", "active")


class TB:
    """Inputs change and outputs are read at falling edges; step() is one rising edge.

    Every output is compared with the model on every clock; the pin history
    is kept for the measurements, which do not use the model.
    """

    def __init__(self, dut) -> None:
        self.dut = dut
        self.n = int(dut.PWM_BITS.value)
        self.m = full_scale(self.n)
        self.model = PwmTorqueModel(self.n)
        self.inp = PwmInputs(enable=1)
        self.div = 1
        self._div_count = 0
        self.cycle = 0
        self.history: list[dict[str, int]] = []
        cocotb.start_soon(Clock(dut.clk, 20, unit="ns").start())

    def set(self, **kw) -> None:
        d = {**self.inp.__dict__, **kw}
        self.inp = PwmInputs(**d)

    def _drive(self, rst: int) -> None:
        i = self.inp   # the model's inputs are named as the core's ports
        tbutil.drive(self.dut, rst=rst, **{**asdict(i), "cmd": i.cmd & ((1 << (self.n + 1)) - 1)})

    def read(self) -> dict[str, int]:
        return {k: int(getattr(self.dut, k).value) for k in (*PINS, *STATUS)}

    async def step(self, rst: int = 0) -> dict[str, int]:
        # The test's divider: a tick on every div-th clock.
        self._div_count += 1
        tick = 1 if self._div_count >= self.div else 0
        if tick:
            self._div_count = 0
        self.set(tick=tick)
        self._drive(rst)
        await FallingEdge(self.dut.clk)
        self.cycle += 1
        want = self.model.clock(self.inp, rst).__dict__
        got = self.read()
        diff = {k: (got[k], want[k]) for k in got if got[k] != want[k]}
        assert not diff, f"clock {self.cycle}: (dut, model) differ {diff} for {self.inp}"
        self.history.append(got)
        return got

    async def reset(self) -> None:
        await FallingEdge(self.dut.clk)
        for _ in range(2):
            await self.step(rst=1)
        self._div_count = self.div - 1      # first tick on the next clock
        self.history.clear()

    async def run(self, clocks: int) -> None:
        for _ in range(clocks):
            await self.step()

    async def until_period_start(self, limit: int) -> None:
        for _ in range(limit):
            if (await self.step())["period_start"]:
                return
        raise AssertionError(f"no period start in {limit} clocks")

    @property
    def period(self) -> int:
        return self.div * self.m


def measure(samples: list[int]) -> tuple[list[int], list[int], int]:
    """(periods, high times, constant level or -1) of a pin from its samples.

    samples[0] is the first clock of a period (its level counts as a rising
    edge when high); periods are the clocks between rising edges, high times
    the length of the high run starting at each rising edge."""
    rises = ([0] if samples[0] else []) + [k for k in range(1, len(samples))
                                           if samples[k] and not samples[k - 1]]
    level = samples[0] if len(set(samples)) == 1 else -1
    periods = [b - a for a, b in zip(rises, rises[1:])]
    highs = []
    for a in rises[:-1]:
        h = 0
        while samples[a + h]:
            h += 1
        highs.append(h)
    return periods, highs, level


async def check_pwm_pair(tb: TB, div: int, cmd: int, pw0: int, pw_max: int, dir_mode: int = 0) -> None:
    """Hold one divisor/command; measure period and duty on the active pin over two periods."""
    tb.div = div
    tb.set(cmd=cmd, pw0=pw0, pw_max=pw_max, dir_mode=dir_mode, enable=1, fault=0)
    set_at = tb.cycle
    await tb.until_period_start(tb.period + div + 2)
    if tb.cycle - set_at <= PIPE_CLOCKS:
        # that period start latched the previous command: take the next one
        await tb.until_period_start(tb.period + div + 2)
    start = len(tb.history) - 1
    await tb.run(2 * tb.period)
    hist = tb.history[start:]
    duty = map_duty(cmd, pw0, pw_max, tb.n)
    if dir_mode:
        active_pin, idle_pins = "pwm_out", ("rpwm", "lpwm")
        assert all(h["dir_out"] == (1 if cmd < 0 else 0) for h in hist), "dir_out wrong"
    else:
        active_pin = "lpwm" if cmd < 0 else "rpwm"
        idle_pins = ("rpwm" if cmd < 0 else "lpwm", "pwm_out", "dir_out")
    for p in idle_pins:
        assert all(h[p] == 0 for h in hist), f"{p} not idle for cmd {cmd}"
    assert all(h["r_en"] == 1 and h["l_en"] == 1 for h in hist), "enables dropped while running"
    periods, highs, level = measure([h[active_pin] for h in hist])
    what = f"div={div} cmd={cmd} pw0={pw0} pw_max={pw_max} -> duty {duty}/{tb.m}"
    if duty == 0:
        assert level == 0, f"{what}: {active_pin} not constantly low"
    elif duty == tb.m:
        assert level == 1, f"{what}: {active_pin} not constantly high"
    else:
        assert periods == [div * tb.m] * 2, f"{what}: periods {periods} clocks, want {div * tb.m}"
        assert highs == [duty * div] * 2, f"{what}: high {highs} clocks, want {duty * div}"


@cocotb.test()
async def period_and_duty_on_the_pins(dut):
    tb = TB(dut)
    await tb.reset()
    m = tb.m
    pw0, pw_max = m // 5, m - m // 10
    cases = [
        (1, 0, 0, m),            # zero command: constant low
        (1, m, 0, m),            # full scale: constant high
        (2, -m, 0, m),           # reverse full scale on LPWM
        (1, 1, pw0, pw_max),     # +1 jumps over the dead zone to PW0
        (3, -1, pw0, pw_max),    # -1 likewise, reverse
        (2, m, pw0, pw_max),     # full command lands on PW_F
        (1, -(m + 1), pw0, pw_max),  # -2^N saturates to -M -> PW_F
        (2, m // 2, pw0, pw_max),
        (3, -(m // 3), pw0, pw_max),
        (1, 5, 0, m),            # no dead zone: duty == command
        (2, 7, pw_max, pw0),     # pw_max below PW0: the limit wins
    ]
    cases += [(random.randint(1, 3), random.randint(-m - 1, m), random.randint(0, m // 2),
               random.randint(m // 2, m)) for _ in range(6)]
    for div, cmd, a, b in cases:
        await check_pwm_pair(tb, div, cmd, a, b)
    # PWM + DIR mode
    for div, cmd in ((1, m // 3), (2, -(m // 4)), (1, -m), (1, 0)):
        await check_pwm_pair(tb, div, cmd, pw0, pw_max, dir_mode=1)


@cocotb.test()
async def direction_changes_only_at_period_boundary(dut):
    tb = TB(dut)
    tb.div = 2
    await tb.reset()
    m = tb.m
    tb.set(cmd=m // 2, pw0=0, pw_max=m)
    await tb.until_period_start(tb.period + 10)
    await tb.until_period_start(tb.period + 10)
    fwd_start = len(tb.history) - 1
    # Reverse at a random point inside the period (the pulse is high then or low).
    await tb.run(random.randint(1, tb.period - PIPE_CLOCKS - 2))
    tb.set(cmd=-(m // 3))
    await tb.until_period_start(tb.period + 2)
    rev_start = len(tb.history) - 1
    await tb.run(tb.period)
    assert rev_start - fwd_start == tb.period, "the reversed period did not start on the boundary"
    fwd = tb.history[fwd_start:rev_start]
    rev = tb.history[rev_start:rev_start + tb.period]
    assert sum(h["rpwm"] for h in fwd) == map_duty(m // 2, 0, m, tb.n) * tb.div, \
        "forward pulse cut short by the direction change"
    assert not any(h["lpwm"] for h in fwd), "LPWM rose before the period boundary"
    assert not any(h["rpwm"] for h in rev), "RPWM high after the reversal"
    assert sum(h["lpwm"] for h in rev) == map_duty(-(m // 3), 0, m, tb.n) * tb.div


async def response_within_one_clock(tb: TB, which: str, brake: int, dir_mode: int) -> None:
    """Assert fault (or drop enable) just after a rising edge; the pins must be safe
    by the next rising edge, then stay safe until a period start after release."""
    m = tb.m
    tb.div = 1
    tb.set(cmd=-m if dir_mode else m, pw0=0, pw_max=m, brake_on_fault=brake, dir_mode=dir_mode,
           enable=1, fault=0)
    await tb.until_period_start(tb.period + 10)
    await tb.run(random.randint(1, tb.period - 2))
    d = tb.dut
    # One edge R1 with the running inputs (div = 1: a tick on every clock) ...
    tb.set(tick=1)
    tb._drive(0)
    await RisingEdge(d.clk)
    tb.model.clock(tb.inp)
    # ... then the stop request 2 ns after R1, and the pins timed at R2.
    await Timer(2, unit="ns")
    t0 = cocotb.utils.get_sim_time(unit="ns")
    if which == "fault":
        tb.set(fault=1)
        d.fault.value = 1
    else:
        tb.set(enable=0)
        d.enable.value = 0
    await RisingEdge(d.clk)
    await ReadOnly()
    dt = cocotb.utils.get_sim_time(unit="ns") - t0
    got = {k: int(getattr(d, k).value) for k in PINS}
    assert got == safe_pins(brake, dir_mode), f"{which}: pins {got} {dt} ns after it, not safe"
    assert dt <= 20, f"{which}: safe after {dt} ns"
    want = tb.model.clock(tb.inp).__dict__
    await FallingEdge(d.clk)
    tb.cycle += 2
    got = tb.read()
    assert got == want, f"{which}: outputs {got}, model {want}"
    tb.history.append(got)
    # Hold the stop for a while, release in mid-period: no pulse before the next start.
    await tb.run(random.randint(1, tb.period))
    tb.set(fault=0, enable=1)
    rel = len(tb.history)
    await tb.until_period_start(tb.period + 2)
    resumed = len(tb.history) - 1
    pins_between = tb.history[rel:resumed]
    assert all(h["rpwm"] == 0 and h["lpwm"] == 0 and h["pwm_out"] == 0 for h in pins_between), \
        f"{which}: a pulse before the period start after release"
    await tb.run(tb.period)
    pin = "pwm_out" if dir_mode else "rpwm"
    assert sum(h[pin] for h in tb.history[resumed:resumed + tb.period]) == tb.period, \
        "full period not restored"


@cocotb.test()
async def fault_and_enable_make_pins_safe_within_one_clock(dut):
    tb = TB(dut)
    await tb.reset()
    for which in ("fault", "enable"):
        for brake in (0, 1):
            for dir_mode in (0, 1):
                await response_within_one_clock(tb, which, brake, dir_mode)


@cocotb.test()
async def random_stream_follows_model(dut):
    tb = TB(dut)
    await tb.reset()
    m = tb.m
    for _ in range(6000):
        r = random.random()
        if r < 0.01:
            tb.set(cmd=random.randint(-m - 1, m))
        elif r < 0.013:
            tb.set(cmd=random.choice((0, 1, -1, m, -m, -m - 1)))
        elif r < 0.016:
            tb.set(pw0=random.randint(0, m), pw_max=random.randint(0, m))
        elif r < 0.018:
            tb.set(enable=random.random() < 0.8)
        elif r < 0.020:
            tb.set(fault=random.random() < 0.2)
        elif r < 0.021:
            tb.set(brake_on_fault=random.randint(0, 1), dir_mode=random.randint(0, 1))
        elif r < 0.023:
            tb.div = random.randint(1, 3)
        if r > 0.9995:
            await tb.step(rst=1)
        else:
            await tb.step()
        # Independent of the model: never both PWM inputs of the IBT-2 high.
        h = tb.history[-1]
        assert not (h["rpwm"] and h["lpwm"]), f"clock {tb.cycle}: RPWM and LPWM both high"


@cocotb.test()
async def full_width_duty_table(dut):
    """Only for the PWM_BITS = 10 build: the paper's 1023-count duty at div 1."""
    tb = TB(dut)
    await tb.reset()
    m = tb.m
    for cmd, pw0, pw_max in ((0, 100, m), (m, 100, m), (1, 100, 900), (-(m // 2), 100, 900)):
        await check_pwm_pair(tb, 1, cmd, pw0, pw_max)


@cocotb.test()
async def chain_carrier_matches_ref(dut):
    """freq_div driving pwm_torque (char_bench_top / pwm_chain_top.vhd): the carrier period and pulse
    width on RPWM, timed in ns, equal torqueloop.oracles.freq_div.carrier_hz() and
    map_duty() for the reset default (eq. 4 Count_max) and written divisors."""
    p = FreqDivParams(clk_hz=int(dut.CLK_HZ.value), pwm_bits=int(dut.PWM_BITS.value),
                      div_bits=int(dut.DIV_BITS.value), default_div=int(dut.DEFAULT_DIV.value))
    n, m = p.pwm_bits, full_scale(p.pwm_bits)
    clk_ns = 1e9 / p.clk_hz
    cocotb.start_soon(Clock(dut.clk, clk_ns, unit="ns").start())
    cmd = random.randint(1, m - 1)
    dut.rst.value = 1
    dut.div_we.value = 0
    dut.div_in.value = 0
    dut.cmd.value = cmd
    dut.pw0.value = 0
    dut.pw_max.value = m
    dut.enable.value = 1
    for _ in range(2):
        await RisingEdge(dut.clk)
    await FallingEdge(dut.clk)
    dut.rst.value = 0
    divs = [None, count_max(25_000, p.clk_hz, n, p.div_bits), random.randint(2, 9)]
    for div in divs:
        if div is not None:
            await FallingEdge(dut.clk)
            dut.div_in.value = div
            dut.div_we.value = 1
            await FallingEdge(dut.clk)
            dut.div_we.value = 0
        want_div = p.default_div if div is None else div
        assert int(dut.div.value) == want_div
        # Skip the period the write disturbed, then time two whole periods.
        rises = []
        for _ in range(4):
            await RisingEdge(dut.rpwm)
            rises.append(cocotb.utils.get_sim_time(unit="ns"))
            if len(rises) == 3:
                await FallingEdge(dut.rpwm)
                high_ns = cocotb.utils.get_sim_time(unit="ns") - rises[-1]
        periods = [b - a for a, b in zip(rises[1:], rises[2:])]
        want_period_ns = 1e9 / carrier_hz(want_div, p.clk_hz, n)
        assert periods == pytest.approx([want_period_ns] * 2, abs=1e-3), \
            f"div {want_div}: carrier periods {periods} ns, ref {want_period_ns} ns"
        want_high_ns = map_duty(cmd, 0, m, n) * want_div * clk_ns
        dut._log.info("div %d: carrier %.2f Hz measured, %.2f Hz ref; high %.0f ns", want_div,
                      1e9 / periods[-1], carrier_hz(want_div, p.clk_hz, n), high_ns)
        assert high_ns == pytest.approx(want_high_ns, abs=1e-3), f"div {want_div}: high {high_ns} ns"


# Small periods (PWM_BITS = 6: 63 ticks) keep the run short; one build at the
# paper's 10 bits runs the 1023-count table.
SETS = {
    "n6": ({"PWM_BITS": 6}, ("period_and_duty_on_the_pins", "direction_changes_only_at_period_boundary",
                             "fault_and_enable_make_pins_safe_within_one_clock",
                             "random_stream_follows_model")),
    "n10": ({"PWM_BITS": 10}, ("full_width_duty_table",)),
}


# Every simulator runs the 6-bit set; the 10-bit table skips Verilator, whose
# C++ build (~15 CPU-s) is most of this bench's cost in make test.
CASES = [(sim, "n6") for sim in sims_for("pwm_torque")] + \
        [(sim, "n10") for sim in sims_for("pwm_torque") if sim != "verilator"]


@pytest.mark.parametrize("sim, pset", CASES, ids=[f"{s}-{p}" for s, p in CASES])
def test_pwm_torque(sim, pset):
    params, tests = SETS[pset]
    run("pwm_torque", sim, "test_pwm_torque", parameters=params, testcase=",".join(tests))


CHAIN_DIR = REPO_ROOT / "tb" / "pwm_torque"


@pytest.mark.parametrize("sim", [s for s in sims_for("pwm_torque") if s != "verilator"])
def test_pwm_torque_chain(sim):
    """freq_div + pwm_torque together (Icarus and GHDL: a cheap build each)."""
    from torqueloop.characterize.simbench import CHAR_BENCH_TOP   # the chain the characterisation bench drives

    run("pwm_torque", sim, "test_pwm_torque", toplevel="pwm_chain_top" if sim == "ghdl" else CHAR_BENCH_TOP.stem,
        parameters={"PWM_BITS": 6, "DEFAULT_DIV": count_max(20_000, pwm_bits=6)},
        extra_verilog=[REPO_ROOT / "rtl" / "motion" / "tl_freq_div.v", CHAR_BENCH_TOP],
        extra_vhdl=[REPO_ROOT / "rtl" / "motion" / "tl_freq_div.vhd", CHAIN_DIR / "pwm_chain_top.vhd"],
        testcase="chain_carrier_matches_ref")
