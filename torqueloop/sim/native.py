# SPDX-License-Identifier: MIT
"""Build and drive the native Verilator harness (torqueloop/sim/native/harness.cpp).

The board image is verilated once into a shared library (build/rtl_loop/native/)
and loaded with ctypes; the ROM/RAM images are read by $readmemh when a model
is created, from fixed paths in the build folder, so a new firmware image
needs no rebuild.  The build is skipped when the sources, the harness and the
flags are unchanged (a hash stamp), and serialised with a file lock so
parallel runs never load a half-built library.
"""

from __future__ import annotations

import ctypes
import fcntl
import hashlib
import os
import shutil
import subprocess
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from torqueloop.flow import tools
from torqueloop.flow.manifest import REPO_ROOT, core as manifest_core
from torqueloop.spec.system import SYSTEM

NATIVE_DIR = Path(__file__).resolve().with_name("native")
WRAPPER = REPO_ROOT / "tb" / "rtl_loop" / "rtl_loop_top.v"
BUILD = REPO_ROOT / "build" / "rtl_loop" / "native"
ROM_HEX = BUILD / "image_rom.hex"
RAM_HEX = BUILD / "image_ram.hex"
LIB = BUILD / "libtlcosim.so"
CLK_HZ = SYSTEM.clk_hz
#: -O3 and fast X handling: the harness is a speed path; the cocotb harness and
#: the SoC's own benches keep the checking builds.
VFLAGS = ["--cc", "-O3", "--x-assign", "fast", "--x-initial", "fast", "--noassert", "--no-timing",
          "-Wno-fatal", "-Wno-lint", "-Wno-style", "--top-module", "rtl_loop_top"]


def _verilator() -> str:
    return tools.verilator()


def _verilator_root() -> str:
    r = subprocess.run([_verilator(), "--getenv", "VERILATOR_ROOT"], capture_output=True, text=True, check=True)
    return r.stdout.strip()


def sources() -> list[Path]:
    """Every file of the build, headers included (the stamp hashes them all)."""
    return [REPO_ROOT / p for p in manifest_core("rtl_loop").verilog]   # ends with WRAPPER


def _stamp() -> str:
    h = hashlib.sha1()
    for p in sources() + [NATIVE_DIR / "harness.cpp"]:
        h.update(p.read_bytes())
    h.update(" ".join(VFLAGS).encode())
    h.update(_verilator().encode())
    return h.hexdigest()


def build(verbose: bool = False) -> Path:
    """Verilate and compile the harness library if anything changed."""
    BUILD.mkdir(parents=True, exist_ok=True)
    with open(BUILD / ".lock", "w") as lk:
        fcntl.flock(lk, fcntl.LOCK_EX)
        stamp = _stamp()
        sf = BUILD / "stamp"
        if LIB.exists() and sf.exists() and sf.read_text() == stamp:
            return LIB
        obj = BUILD / "obj"
        shutil.rmtree(obj, ignore_errors=True)
        cmd = [_verilator(), *VFLAGS, "--Mdir", str(obj), "-CFLAGS", "-fPIC -O2",
               f"-GROM_INIT=\"{ROM_HEX}\"", f"-GRAM_INIT=\"{RAM_HEX}\"",
               *(f"-I{d}" for d in manifest_core("rtl_loop").include_dirs),
               *(str(p) for p in sources() if p.suffix != ".vh")]
        out = None if verbose else subprocess.DEVNULL
        subprocess.run(cmd, check=True, stdout=out)
        jobs = str(max(1, min(2, os.cpu_count() or 1)))
        subprocess.run(["make", "-s", "-j", jobs, "-C", str(obj), "-f", "Vrtl_loop_top.mk",
                        "OPT_FAST=-O3 -march=native", "OPT_SLOW=-O1", "OPT_GLOBAL=-O2 -march=native",
                        "Vrtl_loop_top__ALL.a", "libverilated.a"], check=True, stdout=out)
        inc = Path(_verilator_root()) / "include"
        tmp = BUILD / f"libtlcosim.{os.getpid()}.so"
        subprocess.run(["g++", "-shared", "-fPIC", "-O2", "-std=c++17", f"-I{inc}", f"-I{inc / 'vltstd'}",
                        f"-I{obj}", "-o", str(tmp), str(NATIVE_DIR / "harness.cpp"),
                        str(obj / "Vrtl_loop_top__ALL.a"), str(obj / "libverilated.a"), "-pthread"],
                       check=True, stdout=out)
        os.replace(tmp, LIB)
        sf.write_text(stamp)
        return LIB


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
    def create(cls, rom_hex: Path, ram_hex: Path) -> "NativeBoard":
        lib = _load(build())
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
