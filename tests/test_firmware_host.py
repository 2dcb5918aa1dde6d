"""Firmware C on the host: unit tests (gcc, ASan + UBSan), control.c against
the Python reference torqueloop/ref/servo.py on random inputs, the physical
gain conversion against torqueloop/protocol.py, a bounded libFuzzer run of the
receive path (clang; skipped with a message if clang or its fuzzer runtime is
missing), the RV32 build, and the generated files being up to date."""

from __future__ import annotations

import os
import random
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from torqueloop import protocol as P
from torqueloop.ref.servo import Axis, AxisParams

REPO = Path(__file__).resolve().parent.parent
FW = REPO / "firmware"
OUT = REPO / "build" / "firmware" / "host"
SRC = [FW / "tests" / "hal_fake.c", FW / "protocol" / "tl_link.c", FW / "servo" / "control.c",
       FW / "servo" / "servo.c"]
INC = [f"-I{FW / d}" for d in ("protocol", "servo", "tests")]
SAN = ["-fsanitize=address,undefined", "-fno-sanitize-recover=all"]
FUZZ_SECONDS = int(os.environ.get("TL_FUZZ_SECONDS", "10"))


@pytest.fixture(scope="module")
def host_tests() -> Path:
    OUT.mkdir(parents=True, exist_ok=True)
    exe = OUT / "host_tests"
    subprocess.run(["gcc", "-std=c11", "-O1", "-g", "-Wall", "-Wextra", "-Werror", *SAN, *INC,
                    str(FW / "tests" / "test_host.c"), *map(str, SRC), "-o", str(exe)], check=True)
    return exe


def test_host_unit_tests(host_tests: Path) -> None:
    seed = int(os.environ.get("TL_SEED", random.randrange(1, 2**32)))
    r = subprocess.run([str(host_tests), "unit", str(seed)], capture_output=True, text=True)
    print(r.stdout)
    assert r.returncode == 0, f"seed {seed}:\n{r.stdout}\n{r.stderr[-4000:]}"
    assert ", 0 failures" in r.stdout


def _random_run(rng: random.Random) -> tuple[list[str], list[tuple[int, int, int, int]]]:
    p = AxisParams(law=rng.randrange(4), kp_q16=rng.choice([0, rng.randrange(2**31)]) if rng.random() < 0.1
                   else rng.randrange(400_000), kd_q16=rng.randrange(5000), ki_q16=rng.randrange(2_000_000),
                   deadband_q16=rng.choice([0, 0x8000, rng.randrange(0x40000)]), cmd_limit=rng.randrange(1, 1024),
                   vel_mode=rng.randrange(2), vmax_cps=rng.randrange(1, 300_000), amax_cps2=rng.randrange(1, 10**7))
    period = rng.randrange(200, 25_001)
    ax = Axis(p, period)
    lines = [f"P {p.law} {p.kp_q16} {p.kd_q16} {p.ki_q16} {p.deadband_q16} {p.cmd_limit} {p.vel_mode} "
             f"{p.vmax_cps} {p.amax_cps2} {period}"]
    pos, t, edge = rng.randrange(-10**6, 10**6), rng.randrange(2**32), 0
    ax.reset(pos, t)
    lines.append(f"R {pos} {t}")
    edge = t
    expect = []
    for _ in range(rng.randrange(20, 200)):
        if rng.random() < 0.05:
            tgt, trap = pos + rng.randrange(-20000, 20000), rng.randrange(2)
            ax.move(tgt, bool(trap))
            lines.append(f"M {tgt} {trap}")
        t = (t + period * 50 + rng.randrange(-100, 100)) & 0xFFFFFFFF
        if rng.random() < 0.6:
            pos += rng.randrange(-300, 300)
            edge = (t - rng.randrange(period * 50)) & 0xFFFFFFFF
        run = int(rng.random() < 0.9)
        interval = rng.randrange(1, period * 50)
        cmd = ax.step(pos, edge, t, bool(run), interval)
        lines.append(f"S {pos} {edge} {t} {run} {interval}")
        expect.append((cmd, ax.sp_q16, ax.vel_q8, ax.integ_q32))
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
        assert g == w, f"seed {seed}, step {i}: C (cmd, sp_q16, vel_q8, integ_q32) = {g}, reference {w}"


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


def _fuzz_binary() -> Path | None:
    if shutil.which("clang") is None:
        return None
    exe = REPO / "build" / "firmware" / "fuzz" / "fuzz_link"
    exe.parent.mkdir(parents=True, exist_ok=True)
    r = subprocess.run(["clang", "-std=c11", "-g", "-O1", "-fsanitize=fuzzer,address,undefined",
                        "-fno-sanitize-recover=all", *INC, str(FW / "tests" / "fuzz_link.c"), *map(str, SRC),
                        "-o", str(exe)], capture_output=True, text=True)
    return exe if r.returncode == 0 else None


def fuzz_seed_corpus(d: Path) -> None:
    """Valid frames of every command (and noise) as a starting corpus."""
    d.mkdir(parents=True, exist_ok=True)
    for c in P.COMMANDS.values():
        fields = {n: 0 for n, _ in c.req}
        (d / f"{c.name}").write_bytes(P.request(c.name, 1, **fields))
    (d / "hello").write_bytes(b"*HELLO*\x00")


def run_fuzz(seconds: int) -> tuple[int, str]:
    exe = _fuzz_binary()
    if exe is None:
        pytest.skip("clang with libFuzzer not found: apt-get install clang libclang-rt-14-dev")
    corpus = REPO / "build" / "firmware" / "fuzz" / "corpus"
    fuzz_seed_corpus(corpus)
    r = subprocess.run([str(exe), f"-max_total_time={seconds}", "-max_len=512", "-print_final_stats=1",
                        str(corpus)], capture_output=True, text=True, cwd=exe.parent)
    runs = 0
    for ln in r.stderr.splitlines():
        if ln.startswith("stat::number_of_executed_units:"):
            runs = int(ln.split(":")[-1])
    assert r.returncode == 0, r.stderr[-4000:]
    return runs, r.stderr


def test_fuzz_receive_path_bounded() -> None:
    runs, _ = run_fuzz(FUZZ_SECONDS)
    print(f"fuzzed {runs} inputs in {FUZZ_SECONDS} s")
    assert runs > 1000


def test_rv32_image_builds_and_fits() -> None:
    sys.path.insert(0, str(REPO / "scripts"))
    from build_firmware import build
    img = build("servo_check", out=REPO / "build" / "firmware" / "check")
    assert img.text_bytes + img.data_bytes + img.bss_bytes + 4096 < 64 * 1024
    words = img.rom_hex.read_text().split()
    assert words[:2] == ["800002b7", "00028067"], "boot stub: lui t0, 0x80000; jr t0"


def test_generated_files_are_current() -> None:
    for script in ("gen_protocol.py", "gen_linker.py"):
        r = subprocess.run([sys.executable, str(REPO / "scripts" / script), "--check"], capture_output=True, text=True)
        assert r.returncode == 0, r.stdout
