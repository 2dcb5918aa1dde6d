# SPDX-License-Identifier: MIT
"""Build the servo firmware: ELF, raw binary, RAM initialisation file for
$readmemh (one 32-bit word per line, word 0 = RAM base) and a boot-ROM image
for simulations that preload the RAM: its stub arms the hardware watchdog as
the real boot ROM (firmware/boot) does, then jumps to the RAM base, and its
key slot holds the link key (the board's boot ROM is
torqueloop.flow.boot_image's).

    python -m torqueloop.flow.firmware [--name servo] [-D NAME=VALUE ...] [--out DIR] [--key-file FILE]

Outputs go to build/firmware/<name>/.  -D sets build-time defaults, e.g. the
test image: -D TL_DEFAULT_PERIOD_US=1000 -D TL_DEFAULT_BAUD_DIV=49.
The C sources are listed once here (SOURCES).
"""

from __future__ import annotations

import argparse
import os
import shutil
import struct
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path

from torqueloop.spec import auth
from torqueloop.spec import protocol as P
from torqueloop.spec import regs
from torqueloop.spec.repo import REPO_ROOT as REPO

FW = REPO / "firmware"
#: the authentication code the servo firmware, the host builds and the fuzzer share (docs/security.md)
AUTH_SOURCES = [FW / "crypto" / "tl_sha256.c", FW / "protocol" / "tl_keyslot.c", FW / "protocol" / "tl_auth.c"]
#: the servo core (firmware/servo/servo_internal.h says which file holds what): the same C on the board,
#: in the host tests, the fuzzer and the simulated board
SERVO_CORE = [FW / "servo" / n for n in ("control.c", "servo.c", "params.c", "safety.c", "homing.c", "commands.c",
                                          "openloop.c", "store.c")] + [FW / "boot" / "boot_crc.c"]
SOURCES = [FW / "common" / "crt0.S", FW / "common" / "mem.c", FW / "protocol" / "tl_link.c", *AUTH_SOURCES,
           *SERVO_CORE, FW / "servo" / "hal_soc.c", FW / "servo" / "main.c"]
INCLUDES = [FW / "include", FW / "protocol", FW / "crypto", FW / "servo", FW / "boot"]
CFLAGS = ["-march=rv32im_zicsr", "-mabi=ilp32", "-O2", "-ffreestanding", "-nostdlib", "-static",
          "-std=c11", "-Wall", "-Wextra", "-Werror", "-ffunction-sections", "-fdata-sections",
          "-DTL_HAL_SOC_INLINE"]   # hal_soc_inline.h: the control iteration's register accessors inline
CC = "riscv64-unknown-elf-gcc"


def libgcc() -> str:
    """The rv32im/ilp32 multilib's libgcc (64-bit division): GCC 12 picks the
    default rv64 one when -march names an extension (_zicsr) it has no multilib for."""
    return subprocess.run([CC, "-march=rv32im", "-mabi=ilp32", "-print-libgcc-file-name"],
                          capture_output=True, text=True, check=True).stdout.strip()


@dataclass(frozen=True)
class Image:
    elf: Path
    bin: Path
    ram_hex: Path
    rom_hex: Path
    text_bytes: int
    data_bytes: int
    bss_bytes: int


def _lui(rd: int, value: int) -> int:
    return (value & 0xFFFFF000) | (rd << 7) | 0x37


def _addi(rd: int, rs: int, imm: int) -> int:
    return ((imm & 0xFFF) << 20) | (rs << 15) | (rd << 7) | 0x13


def _sw(rs2: int, base: int, off: int) -> int:
    return (((off >> 5) & 0x7F) << 25) | (rs2 << 20) | (base << 15) | (2 << 12) | ((off & 0x1F) << 7) | 0x23


def _li(rd: int, value: int) -> list[int]:
    """lui + addi for any 32-bit value (the addi's immediate is sign-extended)."""
    lo = value & 0xFFF
    lo = lo - 0x1000 if lo & 0x800 else lo
    return [_lui(rd, (value - lo) & 0xFFFFFFFF), _addi(rd, rd, lo)]


def boot_stub_words(entry: int, wdog_cycles: int | None = None) -> list[int]:
    """The boot-ROM stub of a RAM-preloaded simulation: arm the SoC's hardware
    watchdog with the real boot ROM's timeout (SYS.WDOG_LOAD, WDOG_ARM = ARM_KEY,
    then one kick), then ``lui t0, entry; jalr x0, 0(t0)``."""
    from torqueloop.spec import bootproto

    if entry & 0xFFF:
        raise ValueError("entry must be 4 KiB aligned for the stub's jump")
    t0, t1 = 5, 6
    wd = bootproto.ms_to_cycles(bootproto.WDOG_MS) if wdog_cycles is None else wdog_cycles
    words = [_lui(t0, regs.SYS_BASE)]
    for value, ofs in ((wd, regs.SYS_WDOG_LOAD_OFS), (regs.SYS_WDOG_ARM_KEY_ARM_KEY, regs.SYS_WDOG_ARM_OFS),
                       (regs.SYS_WDOG_KICK_KEY_KICK_A, regs.SYS_WDOG_KICK_OFS),
                       (regs.SYS_WDOG_KICK_KEY_KICK_B, regs.SYS_WDOG_KICK_OFS)):
        words += _li(t1, value) + [_sw(t1, t0, ofs)]
    return words + [_lui(t0, entry), (t0 << 15) | 0x67]


def rom_words(key: bytes | None) -> list[int]:
    """The boot ROM's words: the stub that jumps to RAM, and the key slot at its top."""
    rom = boot_stub_words(regs.RAM_BASE)
    slot = auth.key_slot(key)
    rom += [0] * ((regs.BOOT_ROM_SIZE - len(slot)) // 4 - len(rom))
    return rom + [int.from_bytes(slot[i:i + 4], "little") for i in range(0, len(slot), 4)]


def build(name: str = "servo", defines: dict[str, str] | None = None, out: Path | None = None,
          ram_bytes: int = regs.RAM_SIZE, key: bytes | None = None) -> Image:
    """``key``: the link key the stub ROM's key slot holds (None: a board without a key)."""
    out = out or REPO / "build" / "firmware" / name
    out.mkdir(parents=True, exist_ok=True)
    elf, binf = out / f"{name}.elf", out / f"{name}.bin"
    ram_hex, rom_hex = out / f"{name}_ram.hex", out / f"{name}_rom.hex"
    # Built under names of this process's own and renamed into place at the end:
    # the processes of make run (and pytest-xdist workers) build the same image
    # at once, and none may read a file another is half way through writing.
    tmp = {f: f.with_name(f"{f.name}.{os.getpid()}.tmp") for f in (elf, binf, ram_hex, rom_hex)}
    dflags = [f"-D{k}={v}" for k, v in (defines or {}).items()]
    cmd = [CC, *CFLAGS, *dflags, *(f"-I{i}" for i in INCLUDES), "-T", str(FW / "common" / "link.ld"),
           "-Wl,--gc-sections", "-Wl,--no-warn-rwx-segments", "-o", str(tmp[elf]), *map(str, SOURCES), libgcc()]
    r = subprocess.run(cmd, capture_output=True, text=True)
    if r.returncode:
        raise RuntimeError(f"firmware build failed:\n{' '.join(cmd)}\n{r.stderr}")
    subprocess.run(["riscv64-unknown-elf-objcopy", "-O", "binary", "--remove-section=.bss", str(tmp[elf]),
                    str(tmp[binf])], check=True)
    data = tmp[binf].read_bytes()
    size = subprocess.run(["riscv64-unknown-elf-size", "-A", str(tmp[elf])], capture_output=True, text=True,
                          check=True).stdout
    sec = {ln.split()[0]: int(ln.split()[1]) for ln in size.splitlines() if ln.startswith(".")}
    bss = sec.get(".bss", 0)
    if len(data) + bss + 4096 > ram_bytes:
        raise RuntimeError(f"{name}: {len(data)} + {bss} bytes (+ stack) do not fit {ram_bytes} bytes of RAM")
    data += bytes(ram_bytes - len(data))
    words = [int.from_bytes(data[i:i + 4], "little") for i in range(0, len(data), 4)]
    tmp[ram_hex].write_text("".join(f"{w:08x}\n" for w in words))
    tmp[rom_hex].write_text("".join(f"{w:08x}\n" for w in rom_words(key)))
    for final, t in tmp.items():
        os.replace(t, final)
    return Image(elf, binf, ram_hex, rom_hex, sec.get(".text", 0) + sec.get(".rodata", 0),
                 sec.get(".data", 0) + sec.get(".sdata", 0), bss)


# --- the link parser under libFuzzer (host build, clang + sanitizers) ------------

#: the firmware C that runs on the host (tests, fuzzing) with the fake HAL
HOST_SOURCES = [FW / "tests" / "hal_fake.c", FW / "protocol" / "tl_link.c", *AUTH_SOURCES, *SERVO_CORE]
HOST_INCLUDES = [f"-I{FW / d}" for d in ("protocol", "crypto", "servo", "boot", "tests")]


class FuzzerMissing(RuntimeError):
    """clang with libFuzzer is not installed."""


class FuzzFailure(RuntimeError):
    """The fuzzer found a crash or a sanitizer report."""


def fuzz_binary() -> Path:
    if shutil.which("clang") is None:
        raise FuzzerMissing("clang with libFuzzer not found: apt-get install clang libclang-rt-14-dev")
    exe = REPO / "build" / "firmware" / "fuzz" / "fuzz_link"
    exe.parent.mkdir(parents=True, exist_ok=True)
    tmp = exe.with_name(f"{exe.name}.{os.getpid()}")   # renamed into place: another process may run the old one
    r = subprocess.run(["clang", "-std=c11", "-g", "-O1", "-fsanitize=fuzzer,address,undefined",
                        "-fno-sanitize-recover=all", *HOST_INCLUDES, str(FW / "tests" / "fuzz_link.c"),
                        *map(str, HOST_SOURCES), "-o", str(tmp)], capture_output=True, text=True)
    if r.returncode:
        raise FuzzerMissing(f"clang could not build the fuzz target (libclang-rt-14-dev missing?):\n{r.stderr[-2000:]}")
    os.replace(tmp, exe)
    return exe


def fuzz_seed_corpus(d: Path) -> None:
    """A starting corpus for both speakers of firmware/tests/fuzz_link.c: the
    attacker (first byte even) with valid untagged frames of every command and
    noise, the key holder (first byte odd) with every command as a frame spec
    [flags seq cmd len payload], tagged, and a session reopened and a replay."""
    d.mkdir(parents=True, exist_ok=True)
    for c in P.COMMANDS.values():
        fields = {n: (bytes(16) if t == "b16" else 0) for n, t in c.req}
        (d / f"{c.name}").write_bytes(b"\x00" + P.request(c.name, 1, **fields))
        payload = struct.pack(c.req_fmt, *fields.values())
        specs = b"".join(bytes([flags]) + struct.pack("<HBB", seq, c.cmd, len(payload)) + payload
                         for flags, seq in ((1, 2), (5, 3), (9, 4), (3, 5)))
        (d / f"{c.name}_auth").write_bytes(b"\x01" + specs)
    # a tagged MOVE, then frames without the key walking the link's seq round, then the MOVE again
    mv = struct.pack("<BHBB", 1, 2, P.COMMANDS["MOVE"].cmd, 6) + bytes(6)
    walk = b"".join(struct.pack("<BHBB", 0, seq, P.COMMANDS["STATUS"].cmd, 1) + b"\x00"
                    for seq in (0x7002, 0xE002, 0x5002, 0xC002))
    (d / "replay_after_seq_walk").write_bytes(b"\x01" + mv + walk + mv)
    (d / "hello").write_bytes(b"\x00*HELLO*\x00")


def run_fuzz(seconds: int) -> tuple[int, str]:
    """(inputs run, fuzzer log) of a bounded run; FuzzFailure on a finding."""
    exe = fuzz_binary()
    corpus = REPO / "build" / "firmware" / "fuzz" / "corpus"
    fuzz_seed_corpus(corpus)
    r = subprocess.run([str(exe), f"-max_total_time={seconds}", "-max_len=512", "-print_final_stats=1",
                        str(corpus)], capture_output=True, text=True, cwd=exe.parent)
    runs = 0
    for ln in r.stderr.splitlines():
        if ln.startswith("stat::number_of_executed_units:"):
            runs = int(ln.split(":")[-1])
    if r.returncode:
        raise FuzzFailure(r.stderr[-4000:])
    return runs, r.stderr


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--name", default="servo")
    ap.add_argument("-D", dest="defines", action="append", default=[], metavar="NAME=VALUE")
    ap.add_argument("--out", type=Path)
    ap.add_argument("--key-file", help=f"the link key for the stub ROM's key slot [${auth.KEY_FILE_ENV}; none]")
    args = ap.parse_args(argv)
    defines = dict(d.split("=", 1) if "=" in d else (d, "1") for d in args.defines)
    path = auth.key_file_path(args.key_file)
    img = build(args.name, defines, args.out, key=auth.read_key_file(path) if path else None)
    for p in (img.elf, img.bin, img.ram_hex, img.rom_hex):
        print(p.relative_to(REPO) if p.is_relative_to(REPO) else p)
    print(f"text+rodata {img.text_bytes} B, data {img.data_bytes} B, bss {img.bss_bytes} B")
    return 0


if __name__ == "__main__":
    sys.exit(main())
