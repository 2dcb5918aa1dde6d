# SPDX-License-Identifier: MIT
"""Trip times at the pins (docs/safety.md): for every fault, the time from the
cause on a board pin (or the last host command, or the hang of the firmware)
to the moment the bridge pins of the driving axis stop driving - RPWM/LPWM
no longer switch (firmware faults: the axis disabled, its bridge braked or
coasting) - and, where the hardware acts, to all four IBT-2 inputs low.

The whole board image (rtl/board/de0_cv_top.v: CPU, SoC, drive interlock,
e-stop gate) runs on the native Verilator harness (torqueloop/sim/harness/harness.cpp)
with the real servo firmware, started by the boot-ROM stub that arms the
hardware watchdog as the boot ROM does; the host talks the link protocol on
the UART pins.  Axis 0 holds a step of 300 counts at a 24.4 kHz carrier
(P law), so its RPWM switches until a fault stops it; the encoder pins are
driven by the bench (no plant: a stage that does not move).  The hung
firmware is tb/rtl_loop/prog/hang.c: it drives axis 0, feeds the watchdog,
then spins with interrupts off.

Each figure is one measurement in clock cycles of CLOCK_50 (20 ns) and in
time; the bounds asserted are the designed ones (docs/safety.md)."""

from __future__ import annotations

import subprocess
import sys
import time
from pathlib import Path

import numpy as np

from torqueloop.flow.firmware import CC, CFLAGS, boot_stub_words, build
from torqueloop.sim import native
from torqueloop.sim.link import SimTransport, sim_client
from torqueloop.spec import auth, bootproto, regs
from torqueloop.spec import protocol as P
from torqueloop.spec.repo import REPO_ROOT as REPO

CLK = regs.CLK_HZ
PERIOD_US = 1000
BAUD_DIV = 49                         # 1 Mbaud: frames take microseconds
FDIV = 2                              # 24.4 kHz, 2046 clocks per PWM period
PWM_PERIOD = FDIV * 1023
DRIVE0 = 0b0011                       # axis 0 RPWM, LPWM
ALL0 = 0b1111                         # axis 0 RPWM, LPWM, R_EN, L_EN
QUAD = [(0, 0), (1, 0), (1, 1), (0, 1)]
STEP = 400                            # clocks per encoder count: above the decoder's 150-clock filter


def _servo_images() -> tuple[Path, Path]:
    img = build("servo_safety_bench", {"TL_DEFAULT_PERIOD_US": str(PERIOD_US), "TL_DEFAULT_BAUD_DIV": str(BAUD_DIV)},
                out=REPO / "build" / "bench_safety" / "servo", key=auth.TEST_KEY)
    return img.rom_hex, img.ram_hex


def _hang_images(hang_at: int) -> tuple[Path, Path]:
    out = REPO / "build" / "bench_safety" / "hang"
    out.mkdir(parents=True, exist_ok=True)
    elf, binf = out / "hang.elf", out / "hang.bin"
    fw = REPO / "firmware"
    subprocess.run([CC, *CFLAGS, f"-DHANG_AT_CYCLES={hang_at}u", "-I", str(fw / "include"),
                    "-T", str(fw / "common" / "link.ld"), "-Wl,--no-warn-rwx-segments", "-o", str(elf),
                    str(fw / "common" / "crt0.S"), str(REPO / "tb" / "rtl_loop" / "prog" / "hang.c")],
                   check=True, capture_output=True, text=True)
    data = bootproto.load_image(elf)
    ram = out / "hang_ram.hex"
    ram.write_text(bootproto.hex_words(data + bytes(regs.RAM_SIZE - len(data))))
    rom = out / "hang_rom.hex"
    words = boot_stub_words(regs.RAM_BASE)
    rom.write_text("".join(f"{w:08x}\n" for w in words + [0] * (regs.BOOT_ROM_SIZE // 4 - len(words))))
    return rom, ram


class Bench:
    """One board image on the native harness, powered up and armed (SW[0] up
    once the boot-ROM stub has armed the watchdog), with the host link."""

    def __init__(self, rom: Path, ram: Path, link: bool = True) -> None:
        self.b = native.NativeBoard.create(rom, ram)
        self.b.set_uart_div(BAUD_DIV + 1)
        self.enc = [0, 0]
        self.b.set_board(0, 1, 0)
        self.run(20)
        self.b.set_board(1, 1, 0)
        self.run(40_000)
        self.b.set_board(1, 1, 1)            # SW[0] up: arms the drive interlock (watchdog alive)
        self.run(1_000)
        if link:
            self.link = sim_client(SimTransport(self.b.uart_send, self.b.uart_recv, lambda n: self.run(n),
                                                lambda: self.b.cycle), auth.TEST_KEY)
            self.link.connect()
            self.link.open_session()

    def run(self, n: int) -> None:
        self.b.run(self.b.cycle + n, False)

    def set(self, name: str, value: int, axis: int = 0) -> None:
        self.link.set_param(name, value, axis)

    def drive_axis0(self, kp_q16: int | None = None) -> None:
        """Axis 0 enabled, homed here, holding a 300-count step: RPWM switching."""
        self.set("FDIV", FDIV, 0)
        self.set("LINK_TIMEOUT_MS", 60_000)
        if kp_q16 is not None:
            self.set("KP_Q16", kp_q16, 0)
        self.link.home(0, "here")
        self.link.enable(1)
        self.link.move(0, 300)
        self.run(3 * PERIOD_US * CLK // 1_000_000)
        assert self.driving(), "axis 0 does not drive before the fault"

    def driving(self, cycles: int = 2 * PWM_PERIOD, mask: int = DRIVE0) -> bool:
        end = self.b.cycle + cycles
        while self.b.cycle < end:
            if self.b.pins() & mask:
                return True
            self.b.run(end, True)
        return bool(self.b.pins() & mask)

    def stop_time(self, t0: int, mask: int = DRIVE0, limit: int = 20_000_000, quiet: int = 3 * PWM_PERIOD,
                  also: int | None = None) -> int | tuple[int, int]:
        """Clocks from t0 to the last time the pins in ``mask`` went inactive
        (they then stayed inactive for ``quiet`` clocks); -1 past ``limit``.
        With ``also``, the same for a second mask, measured in the same pass."""
        masks = [mask] + ([also] if also is not None else [])
        last_off = [t0 if not self.b.pins() & m else -1 for m in masks]
        while self.b.cycle - t0 < limit:
            pins = self.b.pins()
            for i, m in enumerate(masks):
                if pins & m:
                    last_off[i] = -1
                elif last_off[i] < 0:
                    last_off[i] = self.b.cycle
            if all(o >= 0 and self.b.cycle - o >= quiet for o in last_off):
                break
            self.b.run(min(self.b.cycle + quiet, t0 + limit), True)
        out = [o - t0 if o >= 0 and self.b.cycle - o >= quiet else -1 for o in last_off]
        return out[0] if also is None else (out[0], out[1])

    def encoder(self, axis: int, steps: int, spacing: int = 200, illegal: bool = False) -> None:
        """Turn the encoder pins by ``steps`` counts now (A leading B counts up)."""
        cycles, ax, a, b = [], [], [], []
        c = self.b.cycle + spacing
        for _ in range(abs(steps)):
            self.enc[axis] += 1 if steps > 0 else -1
            s = QUAD[self.enc[axis] % 4]
            cycles.append(c), ax.append(axis), a.append(s[0]), b.append(s[1])
            c += spacing
        if illegal:                           # A and B change together
            s = QUAD[(self.enc[axis] + 2) % 4]
            cycles.append(c), ax.append(axis), a.append(s[0]), b.append(s[1])
        self.b.push_edges(np.array(cycles), np.array(ax), np.array(a), np.array(b), np.zeros(len(a), int))

    def close(self) -> None:
        self.b.close()


def _us(c: int) -> str:
    return "n/a" if c < 0 else (f"{c / CLK * 1e3:.3f} ms" if c >= CLK // 1000 else f"{c / CLK * 1e9:.0f} ns")


def main() -> int:
    t_start = time.monotonic()
    rom, ram = _servo_images()
    rows: list[tuple[str, str, int, int, str]] = []   # fault, cause, clocks, bound, what stops

    def record(name: str, cause: str, clocks: int, bound: int, what: str) -> None:
        rows.append((name, cause, clocks, bound, what))
        print(f"  {name:<28} {clocks:>10} clocks  {_us(clocks):>12}   (bound {_us(bound)})", flush=True)

    print(f"[bench_safety] board image + servo firmware on the native Verilator harness, "
          f"PERIOD_US {PERIOD_US}, PWM {CLK / PWM_PERIOD / 1e3:.1f} kHz", flush=True)

    # KEY[0]: combinational to every pin (tl_estop_gate); the interlock then disarms
    s = Bench(rom, ram)
    s.drive_axis0()
    while not s.b.pins() & 0b0100:
        s.run(1)
    t0 = s.b.cycle
    s.b.set_board(1, 0, 1)                      # KEY[0] pressed
    s.run(1)
    record("e-stop (KEY0), all 4 inputs", "KEY0 pin pressed", s.stop_time(t0, ALL0), 1, "every IBT-2 input low")
    s.close()

    # Bridge fault: the SoC latch drops the PWM pins at once, the interlock disarms after its filter
    s = Bench(rom, ram)
    s.drive_axis0()
    t0 = s.b.cycle
    s.b.set_board(1, 1, 1, fault_n=0b10)
    pwm, every = s.stop_time(t0, DRIVE0, also=ALL0)
    record("bridge fault, PWM pins", "fault_n pin low", pwm, 5, "RPWM/LPWM low (SoC latch)")
    record("bridge fault, all 4 inputs", "fault_n pin low", every, 260, "interlock disarmed")
    s.close()

    # Following error: the encoder slips 600 counts back (FOLLOW_LIMIT 500)
    period = PERIOD_US * CLK // 1_000_000
    s = Bench(rom, ram)
    s.set("FOLLOW_LIMIT", 500, 0)
    s.drive_axis0()
    s.encoder(0, -600, spacing=STEP)
    t0 = s.b.cycle + 201 * STEP                # the 501st count of error (the step holds 300)
    record("following error", "encoder pins: error > limit", s.stop_time(t0), period + 1000, "axis disabled")
    s.close()

    # Soft limit: the encoder runs past SOFT_MAX = 350
    s = Bench(rom, ram)
    s.drive_axis0()
    s.set("SOFT_MAX", 350, 0)
    s.encoder(0, 360, spacing=STEP)
    t0 = s.b.cycle + 351 * STEP
    record("soft limit", "encoder pins: position > max", s.stop_time(t0), period + 1000, "axis disabled")
    s.close()

    # Illegal encoder transition
    s = Bench(rom, ram)
    s.drive_axis0()
    s.encoder(0, 0, illegal=True)
    t0 = s.b.cycle + 200
    record("encoder (illegal transition)", "A and B change together", s.stop_time(t0), period + 1000,
           "axis disabled")
    s.close()

    # Limit switch: the hardware block (debounce 1 ms), then the firmware's fault
    s = Bench(rom, ram)
    s.drive_axis0()
    t0 = s.b.cycle
    s.b.set_limits(0, 0b01)                      # the positive switch of axis 0 opens
    record("limit switch (+), RPWM", "switch pin opens", s.stop_time(t0), 50_010, "RPWM held low (SoC block)")
    s.run(2 * period)
    st = s.link.status(0)
    assert st["faults"] == P.FAULT["LIMIT_POS"] and not st["enabled"], st
    s.close()

    # Runaway: the encoder never moves under a command of 300 steps (STALL_MS 50)
    s = Bench(rom, ram)
    s.set("STALL_MS", 50, 0)
    s.drive_axis0(kp_q16=65536)
    # the move is the last command of drive_axis0; its reply came before the 3 periods it waits
    t0 = s.b.cycle - 3 * period
    t = s.stop_time(t0)
    record("runaway (frozen encoder)", "command >= STALL_CMD, no motion", t, 50 * CLK // 1000 + 3 * period,
           "axis disabled")
    assert s.link.status(0)["faults"] == P.FAULT["RUNAWAY"]
    s.close()

    # Link watchdog: silence after the last MOVE (LINK_TIMEOUT_MS 20; polls do not feed it)
    s = Bench(rom, ram)
    s.drive_axis0()
    s.set("LINK_TIMEOUT_MS", 20)
    s.link.heartbeat()
    t0 = s.b.cycle
    t = s.stop_time(t0, limit=5 * CLK // 100)
    record("link watchdog (20 ms)", "last HEARTBEAT", t, 20 * CLK // 1000 + 2 * period, "axis disabled")
    s.close()

    # Hung firmware: hang.c feeds the watchdog until 40 ms, then spins with interrupts off
    hang_at = 2_000_000
    hrom, hram = _hang_images(hang_at)
    s = Bench(hrom, hram, link=False)
    assert s.driving(), "hang.c does not drive axis 0"
    s.run(hang_at - s.b.cycle)
    wd = bootproto.ms_to_cycles(bootproto.WDOG_MS)
    record("hung firmware, all 4 inputs", "last watchdog feed (hang)", s.stop_time(hang_at, ALL0, limit=2 * wd),
           wd + 100, "watchdog: SoC latch + interlock")
    s.b.set_board(1, 1, 0)
    s.run(100)
    s.b.set_board(1, 1, 1)                       # re-arm attempt while it hangs
    assert not s.driving(4 * PWM_PERIOD, ALL0), "re-armed a hung firmware"
    s.close()

    bad = [r for r in rows if r[2] < 0 or r[2] > r[3]]
    print("\n| fault | cause (at the pins) | trip | clocks | what stops |")
    print("|---|---|---:|---:|---|")
    for name, cause, clocks, _bound, what in rows:
        print(f"| {name} | {cause} | {_us(clocks)} | {clocks} | {what} |")
    print(f"[bench_safety] {len(rows)} trips measured in {time.monotonic() - t_start:.0f} s")
    for r in bad:
        print(f"[bench_safety] FAIL {r[0]}: {r[2]} clocks, bound {r[3]}")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
