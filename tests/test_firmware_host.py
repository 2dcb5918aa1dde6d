# SPDX-License-Identifier: MIT
"""Firmware C on the host: unit tests (gcc, ASan + UBSan), control.c against
the Python reference torqueloop/oracles/servo.py on random inputs, the physical
gain conversion against torqueloop/spec/protocol.py, a bounded libFuzzer run of the
receive path (clang; skipped with a message if clang or its fuzzer runtime is
missing) and the RV32 build."""

from __future__ import annotations

import dataclasses
import os
import random
import re
import subprocess
from pathlib import Path

import pytest

from torqueloop.spec import protocol as P
from torqueloop.flow.firmware import HOST_INCLUDES, HOST_SOURCES, FuzzerMissing, run_fuzz
from torqueloop.oracles.servo import DCOUNT_MAX, Axis, AxisParams, edge_speed_q8

REPO = Path(__file__).resolve().parent.parent
FW = REPO / "firmware"
OUT = REPO / "build" / "firmware" / "host"
SRC = HOST_SOURCES
INC = HOST_INCLUDES
SAN = ["-fsanitize=address,undefined", "-fno-sanitize-recover=all"]
FUZZ_SECONDS = int(os.environ.get("TL_FUZZ_SECONDS", "10"))


@pytest.fixture(scope="module")
def host_tests() -> Path:
    OUT.mkdir(parents=True, exist_ok=True)
    exe = OUT / "host_tests"
    # Built under a per-process name and renamed into place: another xdist
    # worker may be running the previous binary (writing it in place failed
    # with "Text file busy").
    tmp = OUT / f"host_tests.{os.getpid()}"
    subprocess.run(["gcc", "-std=c11", "-O1", "-g", "-Wall", "-Wextra", "-Werror", *SAN, *INC,
                    str(FW / "tests" / "test_host.c"), *map(str, SRC), "-o", str(tmp)], check=True)
    os.replace(tmp, exe)
    return exe


def test_host_unit_tests(host_tests: Path) -> None:
    seed = int(os.environ.get("TL_SEED", random.randrange(1, 2**32)))
    r = subprocess.run([str(host_tests), "unit", str(seed)], capture_output=True, text=True)
    print(r.stdout)
    assert r.returncode == 0, f"seed {seed}:\n{r.stdout}\n{r.stderr[-4000:]}"
    assert ", 0 failures" in r.stdout


def _i32(x: int) -> int:
    return ((x + (1 << 31)) & 0xFFFF_FFFF) - (1 << 31)


def _random_run(rng: random.Random, start: int | None = None) -> tuple[list[str], list[tuple[int, int, int, int]]]:
    p = AxisParams(law=rng.randrange(4), kp_q16=rng.choice([0, rng.randrange(2**31)]) if rng.random() < 0.1
                   else rng.randrange(400_000), kd_q16=rng.randrange(5000), ki_q16=rng.randrange(2_000_000),
                   deadband_q16=rng.choice([0, 0x8000, rng.randrange(0x40000)]), cmd_limit=rng.randrange(1, 1024),
                   vel_mode=rng.randrange(2), vmax_cps=rng.randrange(1, 300_000), amax_cps2=rng.randrange(1, 10**7))
    if rng.random() < 0.5:       # the friction compensation's terms (control_step.h friction_terms, izone)
        p = dataclasses.replace(p, fc_pos=rng.choice([0, rng.randrange(1024)]), fc_neg=rng.choice([0, rng.randrange(1024)]),
                                izone_q16=rng.choice([0, rng.randrange(0x80000), rng.randrange(2**31)]),
                                kvff_q16=rng.choice([0, rng.randrange(5000), rng.randrange(0x100_0000)]))
    if rng.random() < 0.3:       # the dither (control_step.h friction_terms), alone or with the terms above
        p = dataclasses.replace(p, dither_amp=rng.choice([1, rng.randrange(1, 64), rng.randrange(1, 1024)]),
                                dither_half=rng.choice([1, 2, rng.randrange(1, 50), rng.randrange(1, 0x10000)]))
    if rng.random() < 0.3:       # the acceleration feed-forward (control_step.h friction_terms), with the rest or alone
        p = dataclasses.replace(p, kaff_q16=rng.choice([1, rng.randrange(1, 5000), rng.randrange(1, 0x100_0000)]))
    period = rng.randrange(200, 25_001)
    ax = Axis(p, period)
    lines = [f"P {p.law} {p.kp_q16} {p.kd_q16} {p.ki_q16} {p.deadband_q16} {p.cmd_limit} {p.vel_mode} "
             f"{p.vmax_cps} {p.amax_cps2} {period} {p.fc_pos} {p.fc_neg} {p.izone_q16} {p.kvff_q16} "
             f"{p.dither_amp} {p.dither_half} {p.kaff_q16}"]
    pos, t, edge = rng.randrange(-10**6, 10**6) if start is None else start, rng.randrange(2**32), 0
    ax.reset(pos, t)
    lines.append(f"R {pos} {t}")
    edge = t
    expect = []
    for _ in range(rng.randrange(20, 200)):
        if rng.random() < 0.05:
            tgt, trap = _i32(pos + rng.randrange(-20000, 20000)), rng.randrange(2)
            ax.move(tgt, bool(trap))
            lines.append(f"M {tgt} {trap}")
        if rng.random() < 0.01:      # a new VMAX / AMAX, mid-move or not: the profile plans again
            p.vmax_cps, p.amax_cps2 = rng.randrange(1, 300_000), rng.randrange(1, 10**7)
            ax.derive()
            lines.append(f"P {p.law} {p.kp_q16} {p.kd_q16} {p.ki_q16} {p.deadband_q16} {p.cmd_limit} {p.vel_mode} "
                         f"{p.vmax_cps} {p.amax_cps2} {period} {p.fc_pos} {p.fc_neg} {p.izone_q16} {p.kvff_q16} "
                         f"{p.dither_amp} {p.dither_half} {p.kaff_q16}")
        t = (t + period * 50 + rng.randrange(-100, 100)) & 0xFFFFFFFF
        if rng.random() < 0.6:
            pos = _i32(pos + rng.randrange(-300, 300))   # the decoder's 32-bit counter wraps
            edge = (t - rng.randrange(period * 50)) & 0xFFFFFFFF
        run = int(rng.random() < 0.9)
        interval = rng.randrange(1, period * 50)
        cmd = ax.step(pos, edge, t, bool(run), interval)
        lines.append(f"S {pos} {edge} {t} {run} {interval}")
        expect.append((cmd, ax.sp_q16, ax.vel_q8, ax.integ_q32, ax.prof_a_q16))
    return lines, expect


def test_control_matches_the_reference_model(host_tests: Path) -> None:
    seed = int(os.environ.get("TL_SEED", random.randrange(1, 2**32)))
    print(f"seed {seed}")
    rng = random.Random(seed)
    runs = [_random_run(rng) for _ in range(150)]
    script = "\n".join(line for lines, _ in runs for line in lines) + "\n"
    out = subprocess.run([str(host_tests), "ctl"], input=script, capture_output=True, text=True, check=True)
    got = [tuple(int(x) for x in ln.split()) for ln in out.stdout.splitlines()]
    want = [e for _, exp in runs for e in exp]
    assert len(got) == len(want)
    for i, (g, w) in enumerate(zip(got, want)):
        assert g == w, f"seed {seed}, step {i}: C (cmd, sp_q16, vel_q8, integ_q32, prof_a_q16) = {g}, reference {w}"


def test_encoder_check_matches_the_reference_model(host_tests: Path) -> None:
    """firmware/servo/enc_check.h against torqueloop.oracles.servo.EncCheck, period
    by period on random runs: commands that hold, change and reverse, encoders
    that follow, stop, run backwards, jump and wrap."""
    from torqueloop.oracles.servo import EncCheck

    seed = int(os.environ.get("TL_SEED", random.randrange(1, 2**32)))
    print(f"seed {seed}")
    rng = random.Random(seed)
    lines, want = [], []
    for _ in range(200):
        cfg = (rng.randrange(0, 200), rng.randrange(1, 100_000), rng.randrange(1, 5000), rng.randrange(1, 500),
               rng.choice([50, 1000, 25_000]))
        ref = EncCheck(*cfg)
        lines.append("E " + " ".join(map(str, cfg)))
        pos, cmd = rng.randrange(-2**31, 2**31), 0
        for _ in range(rng.randrange(1, 300)):
            if rng.random() < 0.1:
                cmd = rng.randrange(-1023, 1024)
            pos = ((pos + rng.choice([0, 0, 1, -1, rng.randrange(-500, 500), rng.randrange(-2**20, 2**20)])
                    + 2**31) % 2**32) - 2**31
            # the control law's speed estimate saturates to +-(2^31 - 1) (control_step.h)
            vel = rng.randrange(-2**31 + 1, 2**31) if rng.random() < 0.05 else rng.randrange(-10**7, 10**7)
            lines.append(f"e {cmd} {pos} {vel}")
            trip = ref.step(cmd, pos, vel)
            want.append((int(trip), ref.vlo_q8, ref.behind_q24))
    out = subprocess.run([str(host_tests), "ctl"], input="\n".join(lines) + "\n", capture_output=True, text=True,
                         check=True)
    got = [tuple(int(x) for x in ln.split()) for ln in out.stdout.splitlines()]
    assert len(got) == len(want)
    for i, (g, w) in enumerate(zip(got, want)):
        assert g == w, f"seed {seed}, step {i}: C (trip, vlo_q8, behind_q24) = {g}, reference {w}"


def test_control_matches_the_reference_across_the_encoder_wrap(host_tests: Path) -> None:
    """Runs that start next to the 32-bit counter's wrap and cross it: the C
    (UBSan aborts on a signed overflow) and the reference agree on the velocity."""
    seed = int(os.environ.get("TL_SEED", random.randrange(1, 2**32)))
    print(f"seed {seed}")
    rng = random.Random(seed)
    runs = [_random_run(rng, start=rng.choice([2**31 - 1 - rng.randrange(2000), -2**31 + rng.randrange(2000)]))
            for _ in range(40)]
    script = "\n".join(line for lines, _ in runs for line in lines) + "\n"
    out = subprocess.run([str(host_tests), "ctl"], input=script, capture_output=True, text=True)
    assert out.returncode == 0, f"seed {seed}: {out.stderr[-2000:]}"
    got = [tuple(int(x) for x in ln.split()) for ln in out.stdout.splitlines()]
    want = [e for _, exp in runs for e in exp]
    assert got == want, f"seed {seed}: first difference at step " \
        f"{next(i for i, (g, w) in enumerate(zip(got, want)) if g != w)}"


def test_division_matches_python(host_tests: Path, seed: int) -> None:
    """tl_div64_32 (control.c's 64-by-32-bit division from two 32-bit divides)
    against Python integers: the quotient when it fits 32 bits, UINT32_MAX when not."""
    rng = random.Random(seed)
    cases = [(0, 0, 1), (0, 7, 7), (1, 0, 2), (0xFFFF_FFFE, 0xFFFF_FFFF, 0xFFFF_FFFF), (1, 0, 1), (0x7FFF, 0, 0x8000)]
    for _ in range(20_000):
        d = rng.choice([rng.randrange(1, 1 << 16), rng.randrange(1, 1 << 32), (1 << 32) - rng.randrange(1, 100),
                        1 << rng.randrange(32)])
        hi = rng.choice([0, rng.randrange(d), d - 1, rng.randrange(1 << 32)])
        cases.append((hi, rng.randrange(1 << 32), d))
    script = "".join(f"D {h} {lo} {d}\n" for h, lo, d in cases)
    out = subprocess.run([str(host_tests), "ctl"], input=script, capture_output=True, text=True, check=True)
    got = [int(x) for x in out.stdout.split()]
    for (h, lo, d), g in zip(cases, got):
        n = (h << 32) | lo
        want = n // d if n // d < (1 << 32) else (1 << 32) - 1
        assert g == want, f"seed {seed}: {n} / {d}: C {g}, Python {want}"


def test_edge_speed_quantisation_as_documented(seed: int) -> None:
    """The one-divide edge speed (docs/firmware.md, "Control") lies below the exact
    floor(N / dt), N = counts clk 2^8, by less than 2^(k+1) q8 with 2^k < N / 2^31:
    a relative error below 2 dt / 2^31 (1e-6 at one 20 kHz period)."""
    rng = random.Random(seed)
    clk = 50_000_000
    for _ in range(20_000):
        counts = rng.choice([1, rng.randrange(1, 64), rng.randrange(1, 6000), rng.randrange(1, DCOUNT_MAX + 1)])
        dt = rng.choice([rng.randrange(1, 5000), rng.randrange(1, 1 << 24), rng.randrange(1, 1 << 32)])
        n = counts * clk * 256
        k = max(0, n.bit_length() - 32)
        exact = n // dt
        v = edge_speed_q8(counts, dt, clk)
        assert v == min(v, (1 << 31) - 1) and (v == (1 << 31) - 1 or exact - (1 << (k + 1)) < v <= exact), \
            f"seed {seed}: {counts} counts / {dt}: {v}, exact {exact}"
        assert (1 << k) <= max(1, n >> 31), (counts, k)
    assert edge_speed_q8(1, 2500, clk) == 256 * 20_000   # one count per 20 kHz period: exact


def test_velocity_estimate_matches_the_reference_model(host_tests: Path, seed: int) -> None:
    """The edge-timestamp velocity (VEL_MODE 1: one 32-bit divide, the numerator
    from the speed table or, beyond it, computed) and the Euler difference against
    the reference over the whole range of times: counts per sample up to beyond the
    table, edge spans and standstills from one clock to 2^31 clocks."""
    rng = random.Random(seed)
    lines, want = [], []
    for _ in range(60):
        mode, period = rng.randrange(2), rng.choice([50, 200, 25_000, rng.randrange(50, 25_001)])
        p = AxisParams(law=1, kp_q16=0, vel_mode=mode)
        ax = Axis(p, period)
        lines.append(f"P 1 0 0 0 0 1023 {mode} {p.vmax_cps} {p.amax_cps2} {period}")
        pos, t = rng.randrange(-2**31, 2**31), rng.randrange(2**32)
        ax.reset(pos, t)
        lines.append(f"R {pos} {t}")
        edge = t
        for _ in range(40):
            span = 1 << rng.randrange(33)
            t = (t + rng.randrange(1, span + 1)) & 0xFFFF_FFFF
            if rng.random() < 0.6:
                pos = ((pos + rng.choice([1, -1]) * rng.randrange(1, 1 << rng.randrange(1, 12)) + 2**31)
                       % 2**32) - 2**31
                edge = (t - rng.randrange(0, max(1, span))) & 0xFFFF_FFFF
            interval = rng.randrange(1, 1 << rng.randrange(1, 33))
            ax.step(pos, edge, t, False, interval)
            lines.append(f"S {pos} {edge} {t} 0 {interval}")
            want.append(ax.vel_q8)
    # targeted: d counts over dt clocks and the standstill bound after dt3 clocks, dt up to 2^32
    for _ in range(3000):
        ax = Axis(AxisParams(law=1, kp_q16=0, vel_mode=1), 50)
        lines.append(f"P 1 0 0 0 0 1023 1 {ax.p.vmax_cps} {ax.p.amax_cps2} 50")
        pos, t = rng.randrange(-2**31, 2**31 - 200), rng.randrange(2**32)
        d = rng.choice([1, rng.randrange(1, 100), rng.randrange(1, 5000)])
        dt, dt3 = (rng.randrange(1, 1 << rng.randrange(1, 33)) for _ in range(2))
        ax.reset(pos, t)
        lines.append(f"R {pos} {t}")
        for q, e, now in ((pos + 1, t + 5, t + 10), (pos + 1 + d, t + 5 + dt, t + 5 + dt),
                          (pos + 1 + d, t + 5 + dt, t + 5 + dt + dt3)):
            e, now = e & 0xFFFF_FFFF, now & 0xFFFF_FFFF
            ax.step(q, e, now, False, 100)
            lines.append(f"S {q} {e} {now} 0 100")
            want.append(ax.vel_q8)
    out = subprocess.run([str(host_tests), "ctl"], input="\n".join(lines) + "\n", capture_output=True, text=True,
                         check=True)
    got = [int(ln.split()[2]) for ln in out.stdout.splitlines()]
    assert len(got) == len(want)
    for i, (g, w) in enumerate(zip(got, want)):
        assert g == w, f"seed {seed}, sample {i}: C velocity {g}, reference {w}"


def test_gain_conversion_matches_python(host_tests: Path) -> None:
    rng = random.Random(7)
    cases = [(820_000, 2400, 8400, 17134), (960_000, 2080, 8400, 0)] + [
        (rng.randrange(100_000_001), rng.randrange(1, 1_000_001), rng.randrange(1, 1_000_001),
         rng.randrange(2**31)) for _ in range(300)]
    script = "".join(f"G {m} {t} {c} {r}\n" for m, t, c, r in cases)
    out = subprocess.run([str(host_tests), "ctl"], input=script, capture_output=True, text=True, check=True)
    for (m, t, c, r), ln in zip(cases, out.stdout.splitlines()):
        raw, phys = (int(x) for x in ln.split())
        assert raw == P.gain_raw_from_phys(m, t, c), (m, t, c)
        assert phys == P.gain_phys_from_raw(r, t, c), (r, t, c)
    # Table 1 axis x P gain: 0.82 N m/rad at tau_max 2.4 N m -> 0.2614 PWM steps per count
    assert abs(P.gain_raw_from_phys(820_000, 2400, 8400) / 65536 - 0.82 / 2.4 * 1023 / (8400 / 6.283185307)) < 1e-4


def test_fuzz_receive_path_bounded() -> None:
    try:
        runs, _ = run_fuzz(FUZZ_SECONDS)
    except FuzzerMissing as e:
        pytest.skip(str(e))
    print(f"fuzzed {runs} inputs in {FUZZ_SECONDS} s")
    assert runs > 1000


def test_rv32_image_builds_and_fits() -> None:
    from torqueloop.flow.firmware import build
    img = build("servo_check", out=REPO / "build" / "firmware" / "check")
    assert img.text_bytes + img.data_bytes + img.bss_bytes + 4096 < 64 * 1024
    # the boot stub, run on the ISS: arms the watchdog as the boot ROM does, then enters the image
    from torqueloop.oracles.rv32 import Memory, Rv32
    from torqueloop.spec import bootproto, regs
    words = [int(w, 16) for w in img.rom_hex.read_text().split()]
    mem = Memory()
    rom = mem.add_ram(regs.BOOT_ROM_BASE, 64 * 4)
    rom.data[:] = b"".join(w.to_bytes(4, "little") for w in words[:64])
    mem.add_ram(regs.SYS_BASE, 0x1000)
    cpu, stores = Rv32(mem, regs.BOOT_ROM_BASE), []
    while cpu.pc != regs.RAM_BASE and len(stores) < 10:
        cpu.last_store = None
        cpu.step()
        if cpu.last_store:
            stores.append(cpu.last_store[::2])
    assert cpu.pc == regs.RAM_BASE
    assert stores == [(regs.SYS_WDOG_LOAD, bootproto.ms_to_cycles(bootproto.WDOG_MS)),
                      (regs.SYS_WDOG_ARM, regs.SYS_WDOG_ARM_KEY_ARM_KEY),
                      (regs.SYS_WDOG_KICK, regs.SYS_WDOG_KICK_KEY_KICK_A),
                      (regs.SYS_WDOG_KICK, regs.SYS_WDOG_KICK_KEY_KICK_B)], stores




def _call_graph(elf: Path) -> tuple[dict[str, set[str]], set[str]]:
    """Direct calls between the functions of an RV32 ELF (jal targets), and the
    functions that make an indirect call (jalr through a register other than ra's return)."""
    dis = subprocess.run(["riscv64-unknown-elf-objdump", "-d", str(elf)], capture_output=True, text=True,
                         check=True).stdout
    calls: dict[str, set[str]] = {}
    indirect: set[str] = set()
    fn = None
    for line in dis.splitlines():
        m = re.match(r"[0-9a-f]+ <([^>]+)>:", line)
        if m:
            fn = m.group(1)
            calls[fn] = set()
            continue
        m = re.search(r"\tjal\t(?:ra,)?[0-9a-f]+ <([^+>]+)>", line)
        if m and fn:
            calls[fn].add(m.group(1))
        elif fn and re.search(r"\tjalr\t(?!zero,0\(ra\))", line) and "\tret" not in line:
            indirect.add(fn)
    return calls, indirect


def test_control_interrupt_never_divides_64_bit() -> None:
    """No libgcc 64-bit division is reachable from the interrupt handler (the
    control iteration): its formats divide 32-bit numbers only."""
    from torqueloop.flow.firmware import build
    img = build("servo_check", out=REPO / "build" / "firmware" / "check")
    calls, indirect = _call_graph(img.elf)
    seen, todo = set(), ["trap_handler"]
    assert "trap_handler" in calls, "the interrupt handler is not in the image under that name"
    while todo:
        f = todo.pop()
        if f not in seen:
            seen.add(f)
            todo += calls.get(f, ())
    div64 = {"__divdi3", "__udivdi3", "__moddi3", "__umoddi3"}
    assert not seen & div64, f"the interrupt reaches {seen & div64} via {sorted(seen)}"
    assert not seen & indirect, f"indirect calls from the interrupt path are not followed: {seen & indirect}"
    # the walk follows the iteration's calls out of line (homing's, the disable's)
    assert {"tl_servo_tick", "tl_home_tick", "tl_axis_disable"} <= seen, sorted(seen)


@pytest.mark.parametrize("direction", [1, -1], ids=["up", "down"])
def test_profile_acceleration_follows_the_trapezoids_phases(host_tests: Path, direction: int) -> None:
    """The acceleration the feed-forward takes (control_step.h prof_a_q16, as the C
    reports it): +AMAX T^2 toward the move while speeding up (the last step up to
    VMAX T less), 0 cruising, the
    opposite while braking (but for the at most two samples that merge the rest of
    the distance into the braking, within +-AMAX T^2), 0 from the landing on - and the C's set-point moves by the sum of
    these changes, so the sign is the speed's change, not a guess."""
    period, vmax, amax, dist = 1000, 5000, 20_000, 3000 * direction
    ax = Axis(AxisParams(law=1, kp_q16=0, vmax_cps=vmax, amax_cps2=amax), period)
    lines = [f"P 1 0 0 0 0 1023 1 {vmax} {amax} {period}", "R 0 0", f"M {dist} 1"]
    lines += [f"S 0 0 {k * period * 50} 1 1" for k in range(1, 1200)]
    out = subprocess.run([str(host_tests), "ctl"], input="\n".join(lines) + "\n", capture_output=True, text=True,
                         check=True)
    rows = [tuple(int(x) for x in ln.split()) for ln in out.stdout.splitlines()]
    acc = [r[4] * direction for r in rows]            # toward the move
    sp = [r[1] for r in rows]
    a_q16 = ax.amax_q16
    top = acc.index(0)                                # the first sample not speeding up: the cruise
    assert top > 1 and set(acc[:top - 1]) == {a_q16} and 0 < acc[top - 1] <= a_q16   # the last: up to VMAX
    brake = next(k for k in range(top, len(acc)) if acc[k] < 0)
    land = next(k for k in range(brake, len(acc)) if sp[k] == dist << 16)
    assert set(acc[top:brake]) == {0} and brake - top > 10            # a cruise at VMAX
    assert all(-a_q16 <= a <= a_q16 for a in acc[brake:land])
    # braking by AMAX T^2, but for the (at most two) samples that merge the rest of the distance in
    assert acc[brake:land].count(-a_q16) >= land - brake - 3 and land - brake > 10
    assert set(acc[land:]) == {0}
    v = 0
    for k in range(land):                             # the speed is the sum of the changes
        v += acc[k] * direction
        assert sp[k] - (sp[k - 1] if k else 0) == v
