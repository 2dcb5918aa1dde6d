# SPDX-License-Identifier: MIT
"""de0_cv_top: the whole board image with the bridges, encoders and RN-XV on
its header pins (tb/de0_cv_top/de0_cv_top_tb.v is the cable harness), and
the plant model (sim_models) on the bridge pins.

The boot ROM runs prog/careless.c, a firmware that always asks both axes for
torque and acknowledges every stop and fault in the SoC's safety latch at
once.  On the header pins the bench checks what the board must guarantee
whatever the firmware does:
  - after reset, with SW[0] already up, no bridge input is ever driven and
    the plant's motors carry no current and stand still;
  - SW[0] down and up arms the drives: the firmware's PWM reaches the pins
    (axis 1 forward on RPWM, axis 2 reverse on LPWM, enables high) and the
    plant's motor currents and angles follow with the right signs;
  - KEY[0] (e-stop) drops every bridge input with no clock edge (the
    e-stop gate), and they stay low after release although the firmware has
    cleared its latch, until SW[0] is moved down and up again; the motor
    currents decay to zero;
  - a bridge fault lasting 250 clocks trips the same way, a shorter glitch
    does not; so does an open fault line (a broken wire, an unpowered
    comparator: the weak pull-up reads it as a fault), and the drives cannot
    be re-armed while it stays open; axis 2 is built as having no
    comparator (BRIDGE_FAULT_WIRED = 01) and its open line is ignored;
  - the UART on GPIO_0 pins 13/14 carries bytes both ways (the firmware
    echoes each byte plus one; an independent UART model on the RN-XV side);
  - the encoders on pins 7/8 count in the decoder's direction (A leading B
    counts up), shown by the firmware on LEDR[7:0];
  - no spare header pin is driven (four-state simulators only);
  - the firmware hanging with interrupts off (SW[8]) stops feeding the
    hardware watchdog careless.c armed: every bridge input drops within its
    timeout, stays low through a re-arm while it hangs and after it
    recovers, until SW[0] is moved down and up again.
A second test runs the real servo firmware (firmware/servo, built by
torqueloop.flow.firmware with a 1 Mbaud link for simulation speed): it
answers the link protocol's IDENTIFY through the header UART, refuses
ENABLE while KEY[0] is held, and no bridge input moves meanwhile.
A third runs prog/flash_probe.c against the EPCS model (torqueloop/sim/epcs.py)
at the ports of the board top's flash block (u_flash, rtl/board/tl_config_flash.v,
the simulators' side of the ASMI connection): what the flash held is read,
the write-enable latch sets, a page program lands in the model and reads back.
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import cocotb
import pytest
from cocotb.simtime import get_sim_time
from cocotb.triggers import FallingEdge, First, RisingEdge, Timer

from torqueloop.spec import regs
from torqueloop.flow.board_files import CABLE_V, load_pin_table
from torqueloop.flow.simrun import BUILD_ROOT, run, sims_for

import tbutil

HERE = Path(__file__).resolve().parent
RAM_BYTES_TB = 4096
UART_BAUD = 1_000_000          # careless.c sets BAUD_DIV = 49 (tb/soc covers the 115200 default)
FAULT_FILTER_CLKS = 250        # de0_cv_top's drive_interlock
PWM_PERIOD = 1023              # careless.c: FDIV = 1
#: Clocks from a stop request on a pin to all bridge inputs low: two
#: synchroniser flops, the interlock's armed register and its output register.
STOP_LATENCY = 5
#: careless.c's watchdog timeout (HANG_WDOG_CYCLES there).
WDOG_CYCLES = 3000
#: The servo firmware's simulation build: 50 clocks per bit.
SERVO_BAUD_DIV = 49
SERVO_BAUD = 50_000_000 // (SERVO_BAUD_DIV + 1)
#: The firmware sets that divisor near the end of its start-up, measured at
#: 11,900 clocks (when this bench was written); bytes sent earlier are garbled.
#: Then it readies the link key (~55 000 clocks) before it reads the UART.
SERVO_STARTUP_CLOCKS = 80_000


class PlantOnPins:
    """The two-axis plant (sim_models: BTS7960 bridges, DC motors, ball
    screws) driven by the IBT-2 pins of the board image: each time a bridge
    pin changes, or at least every CHUNK_NS, the plant is advanced with the
    pin levels that held since the last update.  Its encoders are not fed
    back (a few milliseconds of simulation turn a motor by less than one
    count); the bench turns the encoder pins itself."""

    CHUNK_NS = 4_000

    def __init__(self, dut) -> None:
        from sim_models.bridge import Pins
        from sim_models.stepper import TwoAxisPlant

        self._pins_type = Pins
        self.dut = dut
        self.plant = TwoAxisPlant(glitch_rate_hz=0.0, seed=1)
        self.pins = [Pins(0, 0, 0, 0), Pins(0, 0, 0, 0)]
        self.t_ns = get_sim_time("ns")
        cocotb.start_soon(self._run())

    def _read(self) -> list:
        raw = {n: getattr(self.dut, n).value for n in ("rpwm", "lpwm", "r_en", "l_en")}
        bits = {n: (int(v) if v.is_resolvable else 0) for n, v in raw.items()}
        return [self._pins_type(*((bits[n] >> a) & 1 for n in ("rpwm", "lpwm", "r_en", "l_en"))) for a in (0, 1)]

    def sync(self) -> None:
        """Advance the plant to now with the pins that held since the last update."""
        now = get_sim_time("ns")
        if now > self.t_ns:
            self.plant.advance((now - self.t_ns) * 1e-9, self.pins)
            self.t_ns = now
        self.pins = self._read()

    async def _run(self) -> None:
        d = self.dut
        while True:
            await First(d.rpwm.value_change, d.lpwm.value_change, d.r_en.value_change,
                        d.l_en.value_change, Timer(self.CHUNK_NS, unit="ns"))
            self.sync()


async def _power_up(dut, sw: int, baud: int, fault_open: int = 0):
    """The cable harness at rest (keys released, no fault, encoders still,
    the RN-XV idle and ready), switches at ``sw``, the fault lines of the
    axes in ``fault_open`` left open, a reset pulse; returns the RN-XV side's
    UART models (source into the FPGA, sink from it)."""
    tbutil.start_clock(dut)
    dut.reset_n.value = 0
    dut.key.value = 0xF
    dut.sw.value = sw
    dut.fault.value = 0b00             # the comparators hold their lines low: healthy
    dut.fault_open.value = fault_open
    dut.lim_neg.value = 0              # limit switches closed
    dut.lim_pos.value = 0
    dut.enc_a.value = 0
    dut.enc_b.value = 0
    dut.enc_z.value = 0
    dut.rnxv_tx.value = 1
    dut.rnxv_rts.value = 0
    source, sink = tbutil.uart_models(dut.rnxv_tx, dut.rnxv_rx, baud)
    await _clocks(dut, 5)
    dut.reset_n.value = 1
    return source, sink


BRIDGE = ("rpwm", "lpwm", "r_en", "l_en")
CLK_NS = tbutil.CLK_NS

# The waits below wake Python on the events that matter (a bridge pin changing, a timer) rather
# than on every clock: each awaited clock edge costs a trip through the simulator's callbacks
# and cocotb's scheduler, which on the whole board image was most of this bench's time.


async def _clocks(dut, n: int) -> None:
    """ClockCycles(dut.clk, n) - the n-th rising edge from now - with three
    wake-ups instead of n: the first edge, a timer to the falling edge before
    the n-th, that edge."""
    await RisingEdge(dut.clk)
    if n > 1:
        await Timer((2 * n - 3) * CLK_NS // 2, unit="ns")
        await RisingEdge(dut.clk)


def _bridge(dut) -> dict[str, int]:
    return {n: int(getattr(dut, n).value) for n in BRIDGE}


def _bridge_changes(dut) -> list:
    return [getattr(dut, n).value_change for n in BRIDGE]


async def _expect_all_low(dut, cycles: int, what: str) -> None:
    """Every bridge input low at the next ``cycles`` falling clock edges, and
    in between: low at the first, and none of them changes until the last
    (so a pulse between two edges fails too)."""
    await FallingEdge(dut.clk)
    t0 = get_sim_time("ns")
    b = _bridge(dut)
    assert not any(b.values()), f"{what}: bridge inputs {b} at cycle 0"
    if cycles > 1:
        end = Timer((cycles - 1) * CLK_NS, unit="ns")
        if await First(end, *_bridge_changes(dut)) is not end:
            raw = {n: str(getattr(dut, n).value) for n in BRIDGE}
            raise AssertionError(f"{what}: bridge inputs {raw} {(get_sim_time('ns') - t0) / CLK_NS:.1f} "
                                 f"clocks after the first of {cycles}")


async def _watch_armed(dut, cycles: int) -> dict[str, int]:
    """How many of the next ``cycles`` falling clock edges find each bridge
    input high: the pins' levels from one change to the next, each counted
    over the falling edges it spans."""
    high = {f"{n}{a}": 0 for n in BRIDGE for a in (0, 1)}
    await FallingEdge(dut.clk)
    t0 = get_sim_time("ns")
    t_end = t0 + (cycles - 1) * CLK_NS                # the last falling edge watched

    def edges_before(t: int) -> int:                 # of the falling edges t0, t0 + CLK_NS, ...
        return min(cycles, max(0, -(-(t - t0) // CLK_NS)))

    since, levels = t0, _bridge(dut)
    while True:
        now = get_sim_time("ns")
        last = now >= t_end
        span = edges_before(t_end + 1 if last else now) - edges_before(since)
        for n, v in levels.items():
            for a in (0, 1):
                high[f"{n}{a}"] += span * ((v >> a) & 1)
        if last:
            return high
        since, levels = now, _bridge(dut)
        await First(Timer(t_end - now, unit="ns"), *_bridge_changes(dut))


#: Quadrature states (A, B) in the order A leads B; each level is held long
#: enough for the decoder's default filter (3 samples of 50 clocks).
_QUAD = [(0, 0), (1, 0), (1, 1), (0, 1)]
STEP_CLOCKS = 300


async def _turn_encoders(dut, steps: list[int]) -> None:
    """Move each axis's encoder by steps[axis] counts (positive: A leads B)."""
    state = [0, 0]
    for i in range(max(abs(s) for s in steps)):
        a = b = 0
        for axis, s in enumerate(steps):
            if i < abs(s):
                state[axis] = (state[axis] + (1 if s > 0 else -1)) % 4
            a |= _QUAD[state[axis]][0] << axis
            b |= _QUAD[state[axis]][1] << axis
        dut.enc_a.value = a
        dut.enc_b.value = b
        await _clocks(dut, STEP_CLOCKS)


async def _arm(dut) -> None:
    sw = int(dut.sw.value)
    dut.sw.value = sw & ~1
    await _clocks(dut, 10)
    dut.sw.value = sw | 1
    await _clocks(dut, STOP_LATENCY)


def _check_driving(high: dict[str, int], cycles: int, what: str) -> None:
    # careless.c: axis 1 at +600 of 1023 (RPWM), axis 2 at -400 (LPWM), PW0 = 0, PW_F = 1023.
    assert high["r_en0"] == high["l_en0"] == cycles and high["r_en1"] == high["l_en1"] == cycles, \
        f"{what}: enables not held high: {high}"
    assert high["lpwm0"] == 0 and high["rpwm1"] == 0, f"{what}: wrong bridge side: {high}"
    duty0, duty1 = high["rpwm0"] / cycles, high["lpwm1"] / cycles
    assert abs(duty0 - 600 / 1023) < 0.05, f"{what}: axis 1 duty {duty0:.3f}, expected {600 / 1023:.3f}"
    assert abs(duty1 - 400 / 1023) < 0.05, f"{what}: axis 2 duty {duty1:.3f}, expected {400 / 1023:.3f}"


@cocotb.test()
async def board_interlock_and_uart_on_the_header_pins(dut):
    # SW[0] already up at power-up (SW[9] just to be different); axis 2 has no
    # fault comparator (BRIDGE_FAULT_WIRED = 01): its line stays open throughout
    source, sink = await _power_up(dut, sw=0x201, baud=UART_BAUD, fault_open=0b10)
    plant = PlantOnPins(dut)

    # 1. Power-up with the arm switch up: the firmware asks for torque, nothing moves.
    await _expect_all_low(dut, 4 * PWM_PERIOD, "after reset, switch up")
    plant.sync()
    for a in (0, 1):
        # (1e-6 rad: numerical rest, against 0.098 rad per encoder count)
        assert plant.plant.current(a) == 0.0 and abs(plant.plant.motor_angle(a)) < 1e-6, \
            f"axis {a + 1} moved before arming: {plant.plant.current(a)} A, {plant.plant.motor_angle(a)} rad"
    assert int(dut.ledr.value) >> 8 == 0, "LEDR[9:8] must show disarmed, no trip"
    if cocotb.SIM_NAME.lower().startswith("icarus"):
        # Four-state: every header pin the pin table does not use must float.
        used = {g.signal for g in load_pin_table().gpio}
        for bus, handle in (("GPIO_0", dut.gpio0_pins), ("GPIO_1", dut.gpio1_pins)):
            bits = str(handle.value)[::-1]      # LogicArray string is MSB first
            for i in range(36):
                if f"{bus}[{i}]" not in used:
                    assert bits[i] in "zZ", f"spare pin {bus}[{i}] is driven ({bits[i]}) by the design"

    # Encoders on header pins 7/8: axis 1 turned 6 steps with A leading (counts
    # up), axis 2 3 steps with B leading (counts down); the firmware shows the
    # low nibbles on LEDR[3:0] / LEDR[7:4].
    await _turn_encoders(dut, [6, -3])
    await _clocks(dut, 200)
    assert int(dut.ledr.value) & 0xFF == ((-3 & 0xF) << 4) | 6, f"LEDR shows {int(dut.ledr.value) & 0xFF:#04x}"

    # 2. Arm: the firmware's PWM reaches the pins.
    await _arm(dut)
    assert (int(dut.ledr.value) >> 8) == 0b10, "LEDR[9] = armed"
    _check_driving(await _watch_armed(dut, 3 * PWM_PERIOD), 3 * PWM_PERIOD, "armed")
    plant.sync()
    i1, i2 = plant.plant.current(0), plant.plant.current(1)
    assert i1 > 0.1 and plant.plant.motor_angle(0) > 0, f"axis 1 not driven forward: {i1} A"
    assert i2 < -0.1 and plant.plant.motor_angle(1) < 0, f"axis 2 not driven in reverse: {i2} A"

    # 3. E-stop: every bridge input low with no clock edge (tl_estop_gate), and off
    # after release until re-armed.
    while not int(dut.r_en.value):
        await FallingEdge(dut.clk)
    await Timer(5, unit="ns")                     # away from any clock edge
    dut.key.value = 0xE
    await Timer(1, unit="ns")
    assert not any(_bridge(dut).values()), f"KEY[0] did not reach the pins without a clock: {_bridge(dut)}"
    await _clocks(dut, STOP_LATENCY)
    await _expect_all_low(dut, PWM_PERIOD, "e-stop pressed")
    dut.key.value = 0xF
    await _expect_all_low(dut, 3 * PWM_PERIOD, "e-stop released, firmware acknowledged, not re-armed")
    plant.sync()
    for a in (0, 1):
        assert plant.plant.current(a) == 0.0, f"axis {a + 1}: {plant.plant.current(a)} A after the stop: torque"
    assert (int(dut.ledr.value) >> 8) == 0b01, "LEDR[8] = tripped, LEDR[9] = disarmed"
    await _arm(dut)
    _check_driving(await _watch_armed(dut, 2 * PWM_PERIOD), 2 * PWM_PERIOD, "re-armed")

    # 4. Bridge faults: a glitch shorter than the filter leaves the drives armed
    # (the SoC's own, unfiltered fault latch still stops the PWM until the
    # firmware acknowledges and the next period starts); a real fault trips both axes.
    dut.fault.value = 0b01
    await _clocks(dut, FAULT_FILTER_CLKS // 2)
    dut.fault.value = 0b00
    await _clocks(dut, STOP_LATENCY)
    assert (int(dut.ledr.value) >> 8) == 0b10, "a fault glitch must not trip the interlock"
    await _clocks(dut, 2 * PWM_PERIOD)
    _check_driving(await _watch_armed(dut, 2 * PWM_PERIOD), 2 * PWM_PERIOD, "after a fault glitch")
    await FallingEdge(dut.clk)
    dut.fault.value = 0b01        # axis 1's comparator releases its line: fault
    await _clocks(dut, FAULT_FILTER_CLKS + STOP_LATENCY)
    assert (int(dut.ledr.value) >> 8) == 0b01, "a lasting fault trips the interlock"
    await _expect_all_low(dut, PWM_PERIOD, "bridge fault")
    dut.fault.value = 0b00
    await _expect_all_low(dut, PWM_PERIOD, "fault gone, not re-armed")
    await _arm(dut)
    await _clocks(dut, 2 * PWM_PERIOD)    # the SoC resumes at a period start
    _check_driving(await _watch_armed(dut, PWM_PERIOD), PWM_PERIOD, "re-armed after fault")

    # 4b. Axis 1's fault line opens (its wire breaks): nothing drives header pin 5,
    # the weak pull-up reads a fault, and the drives stop and stay off - SW[0]
    # moved down and up arms nothing - until the line is driven low again.
    await FallingEdge(dut.clk)
    dut.fault_open.value = 0b11
    await _clocks(dut, FAULT_FILTER_CLKS + STOP_LATENCY)
    assert str(dut.gpio0_pins.value)[::-1][4] == "1", "an open fault line must read 1 (the weak pull-up)"
    assert (int(dut.ledr.value) >> 8) == 0b01, "an open fault line trips the interlock"
    await _expect_all_low(dut, PWM_PERIOD, "fault line open")
    await _arm(dut)
    await _expect_all_low(dut, 2 * PWM_PERIOD, "re-armed while the fault line is open")
    assert (int(dut.ledr.value) >> 9) == 0, "armed with a fault line open"
    dut.fault_open.value = 0b10                  # the wire mended: the comparator holds it low
    await _arm(dut)
    await _clocks(dut, 2 * PWM_PERIOD)
    _check_driving(await _watch_armed(dut, PWM_PERIOD), PWM_PERIOD, "re-armed with the line driven again")

    # 5. UART through the header: bytes in on pin 13, the firmware's answer out on pin 14.
    message = bytes([0x00, 0x41, 0x7E, 0xFE, 0xFF, 0x00])   # 0xFF: the answer is a 0x00 byte
    await source.write(message)
    got = bytearray()
    for _ in message:
        got += await sink.read(1)
    assert got == bytes((b + 1) & 0xFF for b in message), f"UART answered {got!r}"

    # 6. The firmware hangs with interrupts off (SW[8], careless.c): it stops feeding the
    # hardware watchdog, which expires WDOG_CYCLES after its last feed; the interlock
    # drops every bridge input and keeps them low - through re-arm attempts while the
    # firmware hangs, and after it recovers - until SW[0] is moved down and up again.
    _check_driving(await _watch_armed(dut, PWM_PERIOD), PWM_PERIOD, "before the hang")
    await FallingEdge(dut.clk)
    dut.sw.value = int(dut.sw.value) | 0x100
    t0 = tbutil.cycle_now()
    while any(_bridge(dut).values()):
        timeout = Timer(3 * WDOG_CYCLES * CLK_NS, unit="ns")
        assert await First(timeout, *_bridge_changes(dut)) is not timeout, "a hung firmware still drives the bridges"
    t_off = tbutil.cycle_now() - t0
    dut._log.info(f"hung firmware: bridge inputs low {t_off} clocks after the hang (watchdog {WDOG_CYCLES})")
    # the last feed came up to one loop of careless.c (about 40 clocks) after the switch
    # moved, and the interlock adds its 2 clocks
    assert WDOG_CYCLES - 100 <= t_off <= WDOG_CYCLES + 60, t_off
    assert (int(dut.ledr.value) >> 8) == 0b01, "LEDR[8] = tripped, LEDR[9] = disarmed"
    await _arm(dut)
    await _expect_all_low(dut, 2 * PWM_PERIOD, "re-armed while the firmware hangs")
    dut.sw.value = int(dut.sw.value) & ~0x100       # the firmware recovers and feeds the watchdog again
    await _expect_all_low(dut, 2 * PWM_PERIOD, "firmware alive again, not re-armed")
    await _arm(dut)
    await _clocks(dut, 2 * PWM_PERIOD)
    _check_driving(await _watch_armed(dut, PWM_PERIOD), PWM_PERIOD, "re-armed after the hang")


async def _exchange(dut, source, sink, decoder, frame: bytes, cycles: int):
    """Send one request frame over the header UART; return the first reply
    frame (telemetry and other traffic skipped) within ``cycles`` clocks."""
    from torqueloop.spec import protocol

    await source.write(frame)
    for _ in range(cycles // 100):
        await _clocks(dut, 100)
        if not sink.empty():
            # list(): FrameDecoder.feed clears its buffer only when resumed
            # after a yield, so it must always be run to the end.
            for f in list(decoder.feed(sink.read_nowait())):
                assert isinstance(f, protocol.Frame), f"damaged frame from the firmware: {f}"
                if f.cmd & protocol.REPLY_FLAG and f.cmd != protocol.TELEMETRY_CMD:
                    return f
        b = _bridge(dut)
        assert not any(b.values()), f"bridge inputs {b} while talking to the unarmed board"
    raise AssertionError(f"no reply within {cycles} clocks (has the firmware's start-up grown beyond "
                         f"SERVO_STARTUP_CLOCKS = {SERVO_STARTUP_CLOCKS}?)")


@cocotb.test()
async def servo_firmware_answers_the_protocol_on_the_header(dut):
    """The real servo firmware (firmware/servo, 1 Mbaud test build) on the
    board image: IDENTIFY answers through GPIO_0 pins 13/14, and ENABLE is
    refused while KEY[0] is pressed; no bridge input moves meanwhile."""
    from torqueloop.spec import protocol

    source, sink = await _power_up(dut, sw=0x001, baud=SERVO_BAUD)
    decoder = protocol.FrameDecoder()
    await _clocks(dut, SERVO_STARTUP_CLOCKS)

    reply = await _exchange(dut, source, sink, decoder, protocol.request("IDENTIFY", 1), 60_000)
    fields = protocol.decode_reply(reply)
    assert reply.cmd == protocol.COMMANDS["IDENTIFY"].cmd | protocol.REPLY_FLAG and reply.seq == 1
    assert fields["status"] == protocol.STATUS["OK"], fields
    assert fields["proto_version"] == protocol.PROTO_VERSION
    assert fields["axis_count"] == 2 and fields["clk_hz"] == 50_000_000, fields

    # ENABLE needs the key (docs/security.md): a session first, its MAC on the ENABLE
    from torqueloop.spec import auth

    hn = auth.new_host_nonce()
    reply = await _exchange(dut, source, sink, decoder, protocol.request("SESSION", 2, host_nonce=hn), 150_000)
    sess = auth.open_session(auth.TEST_KEY, hn, protocol.decode_reply(reply))
    dut.key.value = 0xE                       # e-stop pressed and held
    await _clocks(dut, 200)
    reply = await _exchange(dut, source, sink, decoder, sess.request("ENABLE", 3, mask=3, enable=1), 100_000)
    assert protocol.decode_reply(reply)["status"] == protocol.STATUS["STATE"], "ENABLE accepted during e-stop"
    await _expect_all_low(dut, 2000, "e-stop held after ENABLE")


@cocotb.test()
async def configuration_flash_through_the_board_top(dut):
    """The SoC's flash port through u_flash (ASMI = 0) to the EPCS model: READ, WRITE
    ENABLE + READ STATUS, PAGE PROGRAM + the WIP poll, READ back (prog/flash_probe.c)."""
    from torqueloop.sim.epcs import Epcs
    from torqueloop.spec import protocol

    slot = protocol.STORE["slot_a"]
    flash = Epcs(program_s=20e-6)
    flash.mem[slot:slot + 4] = bytes([0xFF, 0xF0, 0x5A, 0xFF])     # what an earlier save left there
    tbutil.EpcsPins(dut.dut.u_flash, flash, miso="model_miso")
    source, sink = await _power_up(dut, sw=0, baud=UART_BAUD)
    got = bytearray()
    for _ in range(40):                                  # 4 ms at most; it needs well under 1
        await Timer(100, unit="us")
        while not sink.empty():
            got += sink.read_nowait()
        if len(got) >= 10:
            break
    assert len(got) == 10, f"the probe sent {got.hex()}: it stopped"
    assert got[0:4] == bytes([0xFF, 0xF0, 0x5A, 0xFF]), f"READ through u_flash gave {got[0:4].hex()}"
    assert got[4] & protocol.STORE["status_wel"], f"READ STATUS after WRITE ENABLE: {got[4]:#04x}"
    assert 0 < got[5] < 255, f"WIP polls: {got[5]} (the program time must be seen, and end)"
    programmed = bytes(a & b for a, b in zip([0xFF, 0xF0, 0x5A, 0xFF], [0x54, 0x4C, 0x21, 0x0F]))
    assert got[6:10] == programmed, f"read back {got[6:10].hex()}, want {programmed.hex()} (programming ANDs)"
    assert bytes(flash.mem[slot:slot + 4]) == programmed and flash.log == [("program", slot)], flash.log


def _publish(src: Path, dst: Path) -> Path:
    """Move a freshly built image into place atomically, and only if it
    changed: another make test on the same tree may be loading ``dst``."""
    if dst.exists() and dst.read_bytes() == src.read_bytes():
        src.unlink()
    else:
        src.replace(dst)
    return dst


def build_servo_images() -> tuple[Path, Path]:
    """The servo firmware built by torqueloop.flow.firmware for simulation
    (1 Mbaud link, 1 ms control period): (boot-ROM stub, RAM image)."""
    from torqueloop.spec import auth

    out = BUILD_ROOT / "de0_cv_top" / "servo"
    tmp = out / f"tmp{os.getpid()}"
    tmp.mkdir(parents=True, exist_ok=True)
    auth.write_key_file(tmp / "test.key", auth.TEST_KEY)      # the stub ROM's key slot: the public test key
    subprocess.run([sys.executable, "-m", "torqueloop.flow.firmware", "--name", "servo_sim",
                    "-D", f"TL_DEFAULT_BAUD_DIV={SERVO_BAUD_DIV}", "-D", "TL_DEFAULT_PERIOD_US=1000",
                    "--out", str(tmp), "--key-file", str(tmp / "test.key")], check=True, capture_output=True,
                   text=True)
    images = tuple(_publish(tmp / f"servo_sim_{m}.hex", out / f"servo_sim_{m}.hex") for m in ("rom", "ram"))
    for f in tmp.iterdir():
        f.unlink()
    tmp.rmdir()
    return images


def build_rom_image(name: str) -> Path:
    """Compile prog/<name>.c with the SoC bench's crt0 and linker script into
    a boot-ROM $readmemh image (one 32-bit word per line)."""
    out = BUILD_ROOT / "de0_cv_top" / "prog"
    image = tbutil.soc_prog_sections(HERE / "prog" / f"{name}.c", out, {"rom": []})["rom"]
    assert len(image) <= regs.BOOT_ROM_SIZE, f"{name}: {len(image)} bytes do not fit the boot ROM"
    hexf = out / f"{name}.hex"
    tbutil.write_if_changed(hexf, tbutil.readmemh(image, regs.BOOT_ROM_SIZE))
    return hexf


# Icarus only: a Verilator build of the whole SoC costs about a minute of CPU,
# the SoC's own bench (tb/soc) already runs it on Verilator, and only Icarus
# is four-state (the spare-pin check).
@pytest.mark.parametrize("sim", [s for s in sims_for("de0_cv_top") if s == "icarus"])
def test_de0_cv_top(sim):
    rom = build_rom_image("careless")
    run("de0_cv_top", sim, "test_de0_cv_top", toplevel="de0_cv_top_tb",
        extra_verilog=[CABLE_V, HERE / "de0_cv_top_tb.v"], testcase="board_interlock_and_uart_on_the_header_pins",
        parameters={"RAM_BYTES": RAM_BYTES_TB, "ROM_INIT": f'"{rom}"', "BRIDGE_FAULT_WIRED": 1})


# Verilator: the servo firmware's start-up and a keyed session are about two
# million clocks, 420 s of CPU on Icarus against 45 s (build included) here;
# the pins' four-state checks stay in the test above.
@pytest.mark.parametrize("sim", [s for s in sims_for("de0_cv_top") if s == "verilator"])
def test_de0_cv_top_servo_firmware(sim):
    rom, ram = build_servo_images()
    run("de0_cv_top", sim, "test_de0_cv_top", toplevel="de0_cv_top_tb",
        extra_verilog=[CABLE_V, HERE / "de0_cv_top_tb.v"], testcase="servo_firmware_answers_the_protocol_on_the_header",
        parameters={"RAM_BYTES": regs.RAM_SIZE, "ROM_INIT": f'"{rom}"', "RAM_INIT": f'"{ram}"'})


@pytest.mark.parametrize("sim", [s for s in sims_for("de0_cv_top") if s == "icarus"])
def test_de0_cv_top_configuration_flash(sim):
    rom = build_rom_image("flash_probe")
    run("de0_cv_top", sim, "test_de0_cv_top", toplevel="de0_cv_top_tb",
        extra_verilog=[CABLE_V, HERE / "de0_cv_top_tb.v"], testcase="configuration_flash_through_the_board_top",
        parameters={"RAM_BYTES": RAM_BYTES_TB, "ROM_INIT": f'"{rom}"'})
