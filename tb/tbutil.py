# SPDX-License-Identifier: MIT
"""What the SoC-level test benches share (tb/soc_fabric, tb/soc, tb/firmware,
tb/bootloader, tb/de0_cv_top): the clock, the board inputs at their idle
levels, a bus master with the CPU's handshake, UART models on the pins, and
the atomic writes of the memory images those benches build.

Test modules import it by name (``import tbutil``): tb/conftest.py puts tb/
on the path for pytest, and the cocotb runner hands that path on to the
simulator's Python.
"""

from __future__ import annotations

import logging
import os
import random
import subprocess
from pathlib import Path

import cocotb
from cocotb.clock import Clock
from cocotb.triggers import ClockCycles, FallingEdge, First, ReadOnly, RisingEdge
from cocotb.utils import get_sim_time

from torqueloop.spec import bootproto, regs

#: CLOCK_50's period (the register map's clock)
CLK_NS = 1_000_000_000 // regs.CLK_HZ


def start_clock(dut, clk_ns: int = CLK_NS) -> None:
    """The clock in the simulator's C (cocotb's GPI clock, not its default in
    Python, which wakes the interpreter twice a cycle: on the SoC with its
    firmware that cost several times the simulation itself)."""
    Clock(dut.clk, clk_ns, unit="ns", impl="gpi").start()


def cycle_now(clk_ns: int = CLK_NS) -> int:
    """Clock cycles since time 0, from the simulated time (cheaper than a
    coroutine counting every edge)."""
    return int(get_sim_time("ns")) // clk_ns


def idle_soc_pins(dut, sw: int = 0) -> None:
    """The SoC's (and soc_fabric's) board inputs at rest: keys released
    (active low), no e-stop, no bridge fault, encoders still, limit switches
    closed, UART line idle and the peer ready (CTS_N low); switches at ``sw``."""
    drive(dut, sw=sw, key_n=0xF, estop=0, bridge_fault=0, enc_a=0, enc_b=0, enc_z=0, lim_neg=0, lim_pos=0,
          uart_rx=1, uart_cts_n=0,
          flash_miso=1)          # no flash answering: the line idles high, as an erased one reads


async def reset_then_check(dut, reset_out: str, want: int, cycles: int = 3) -> None:
    """Hold ``rst`` for ``cycles`` clocks, check that output ``reset_out``
    reads ``want`` in reset, and release at the next falling edge."""
    dut.rst.value = 1
    await ClockCycles(dut.clk, cycles)
    await ReadOnly()
    assert int(getattr(dut, reset_out).value) == want, f"{reset_out} in reset: want {want:#x}"
    await FallingEdge(dut.clk)
    dut.rst.value = 0


def drive(dut, **values: int) -> None:
    """Set each named input of ``dut`` to its value."""
    for name, v in values.items():
        getattr(dut, name).value = v


def uart_models(rx_pin, tx_pin, baud: int, quiet: bool = False):
    """An independent UART (cocotbext-uart) on the pins: a source driving
    ``rx_pin`` (into the design) and a sink reading ``tx_pin``.  ``quiet``:
    no log line per byte, which costs more than the simulation on long runs."""
    from cocotbext.uart import UartSink, UartSource

    source = UartSource(rx_pin, baud=baud, bits=8)
    sink = UartSink(tx_pin, baud=baud, bits=8)
    if quiet:
        for log in (source.log, sink.log):
            log.setLevel(logging.WARNING)
    return source, sink


class BusMaster:
    """One CPU bus port of tl_soc_fabric (``ibus`` or ``dbus``), with the
    CPU's contract: req and the request fields held until the one-cycle ack,
    rdata/err valid with it.  Drives and samples on the falling edge; ``hold``
    keeps req high through the ack cycle's edge, as a registered CPU master
    may (random when not given)."""

    def __init__(self, dut, prefix: str, max_wait: int = 8) -> None:
        self.dut = dut
        self.p = prefix
        self.is_dbus = prefix == "dbus"
        self.max_wait = max_wait
        self.sig("req").value = 0
        self.sig("addr").value = 0
        if self.is_dbus:
            self.sig("we").value = 0
            self.sig("be").value = 0
            self.sig("wdata").value = 0
        self.accesses = 0
        self.busy_cycles = 0

    def sig(self, name: str):
        return getattr(self.dut, f"{self.p}_{name}")

    async def access(self, addr: int, we: bool = False, wdata: int = 0, be: int = 0xF,
                     hold: bool | None = None) -> tuple[int, bool, int]:
        """One bus transfer; returns (rdata, err, the cycle of its ack)."""
        assert we is False or self.is_dbus
        self.sig("req").value = 1
        self.sig("addr").value = addr
        if self.is_dbus:
            self.sig("we").value = int(we)
            self.sig("be").value = be
            self.sig("wdata").value = wdata
        for _ in range(self.max_wait):
            await FallingEdge(self.dut.clk)
            self.busy_cycles += 1
            if int(self.sig("ack").value):
                break
        else:
            raise AssertionError(f"{self.p} access to {addr:#010x} never acknowledged (hang)")
        rdata = int(self.sig("rdata").value)
        err = bool(int(self.sig("err").value))
        acked = cycle_now()
        self.accesses += 1
        if hold if hold is not None else random.random() < 0.5:
            await FallingEdge(self.dut.clk)   # keep the old request through the ack cycle's edge
            self.busy_cycles += 1
        self.sig("req").value = 0
        return rdata, err, acked

    async def read(self, addr: int) -> int:
        rdata, err, _ = await self.access(addr)
        assert not err, f"{self.p} read {addr:#010x}: unexpected bus error"
        return rdata

    async def write(self, addr: int, wdata: int, be: int = 0xF) -> None:
        _, err, _ = await self.access(addr, we=True, wdata=wdata, be=be)
        assert not err, f"{self.p} write {addr:#010x}: unexpected bus error"


class EpcsPins:
    """The configuration flash on the SoC's FLASH pins: ``torqueloop.sim.epcs.Epcs``
    (the EPCS command set) behind SPI mode 0 - it samples flash_mosi on each
    rising flash_dclk and drives flash_miso after each falling one, MSB first;
    a command is framed by flash_ncs low.  The model's clock is the simulation's.
    ``miso``: the signal of ``dut`` the model drives (the board top's flash block,
    rtl/board/tl_config_flash.v, has the SoC's lines as ports and ``model_miso``)."""

    def __init__(self, dut, model, miso: str = "flash_miso") -> None:
        self.dut, self.m = dut, model
        self.miso = getattr(dut, miso)
        self.miso.value = 1
        cocotb.start_soon(self._run())

    def _now(self) -> None:
        self.m.t = get_sim_time("ns") * 1e-9

    async def _run(self) -> None:
        d = self.dut
        while True:
            await FallingEdge(d.flash_ncs)
            self._now()
            self.m.select(True)
            back, n, byte = self.m.peek(), 0, 0
            self.miso.value = back >> 7 & 1
            while True:
                await First(RisingEdge(d.flash_dclk), RisingEdge(d.flash_ncs))
                if int(d.flash_ncs.value):
                    break
                byte, n = (byte << 1) | int(d.flash_mosi.value), n + 1
                await First(FallingEdge(d.flash_dclk), RisingEdge(d.flash_ncs))
                if n == 8:
                    self._now()
                    self.m.xfer(byte)
                    back, n, byte = self.m.peek(), 0, 0
                if int(d.flash_ncs.value):
                    break
                self.miso.value = back >> (7 - n) & 1
            self._now()
            self.m.select(False)
            self.miso.value = 1


# --- memory images -------------------------------------------------------------------------

def write_if_changed(path: Path, text: str) -> None:
    """Atomic, and untouched when identical: another test run may be reading
    the same image at this moment (a simulator reading a half-written hex
    file would boot garbage)."""
    path.parent.mkdir(parents=True, exist_ok=True)
    if path.exists() and path.read_text() == text:
        return
    tmp = path.with_name(f"{path.name}.{os.getpid()}.tmp")
    tmp.write_text(text)
    tmp.replace(path)


def readmemh(data: bytes, size: int) -> str:
    """``data`` padded with zeros to a memory of ``size`` bytes, as $readmemh
    text (the one word-per-line writer of torqueloop.spec.bootproto)."""
    assert len(data) <= size, f"{len(data)} bytes do not fit {size}"
    return bootproto.hex_words(data + bytes(size - len(data)))


#: crt0 and linker script of the SoC test programs (code in the boot ROM, 4 KiB of RAM)
SOC_PROG = Path(__file__).resolve().parent / "soc" / "prog"


def soc_prog_sections(source: Path, out_dir: Path, sections: dict[str, list[str]]) -> dict[str, bytes]:
    """Compile a C test program for the SoC (SOC_PROG's crt0 and link.ld,
    the generated register header) and return the raw bytes objcopy makes
    of it with each entry's options (e.g. ``{"rom": ["-R", ".ramtext"]}``).
    Intermediate files carry the process id: parallel runs build side by side."""
    from torqueloop.spec.repo import REPO_ROOT

    out_dir.mkdir(parents=True, exist_ok=True)
    tag = f"{source.stem}.{os.getpid()}"
    elf = out_dir / f"{tag}.elf"
    subprocess.run(
        ["riscv64-unknown-elf-gcc", "-march=rv32im_zicsr", "-mabi=ilp32", "-O2", "-nostdlib",
         "-ffreestanding", "-static", "-std=c11", "-Wall", "-Wextra", "-Werror",
         "-I", str(REPO_ROOT / "firmware" / "include"), "-T", str(SOC_PROG / "link.ld"),
         "-Wl,--no-warn-rwx-segments", "-o", str(elf), str(SOC_PROG / "crt0.S"), str(source)],
        check=True, capture_output=True, text=True)
    out: dict[str, bytes] = {}
    for name, opts in sections.items():
        binf = out_dir / f"{tag}.{name}.bin"
        subprocess.run(["riscv64-unknown-elf-objcopy", "-O", "binary", *opts, str(elf), str(binf)], check=True)
        out[name] = binf.read_bytes()
        binf.unlink()
    elf.replace(out_dir / f"{source.stem}.elf")
    return out


def read_hex(path: Path) -> list[int]:
    return [int(line, 16) for line in path.read_text().split() if line.strip()]
