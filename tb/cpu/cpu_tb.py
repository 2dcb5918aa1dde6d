# SPDX-License-Identifier: MIT
"""cocotb driver of tb/cpu/cpu_sim_top: load an ELF, run to tohost, read memory.

Shared by the CPU test bench (test_cpu.py) and the ELF runner
(scripts/run_elf.py through elf_runner_tb.py).  All waiting happens in the
simulator (RisingEdge of tohost_hit, or a Timer for the cycle limit), so a
long program runs at the simulator's own speed.
"""

from __future__ import annotations

from dataclasses import dataclass

import cocotb
from cocotb.clock import Clock
from cocotb.triggers import First, ReadOnly, RisingEdge, Timer

from torqueloop.oracles.rv32 import Elf
from torqueloop.spec import regs

CLK_NS = 20  # CLOCK_50
RAM_BASE = regs.RAM_BASE  # the SoC's memory map, as cpu_sim_top decodes it


@dataclass
class RunResult:
    tohost: int | None  # None: cycle limit reached first
    cycles: int
    instret: int


class CpuTb:
    def __init__(self, dut) -> None:
        self.dut = dut
        self.ram_bytes = int(dut.RAM_BYTES.value)
        dut.rst.value = 1
        dut.ld_we.value = 0
        dut.ld_addr.value = RAM_BASE
        dut.ld_wdata.value = 0
        dut.wait_states.value = 0
        dut.boot_entry.value = RAM_BASE
        dut.tohost_addr.value = 0
        self.clock = cocotb.start_soon(Clock(dut.clk, CLK_NS, unit="ns").start())

    def image(self, elf: Elf) -> dict[int, int]:
        """Word address -> word of every word an ELF segment touches."""
        mem: dict[int, bytearray] = {}
        for addr, blob in elf.segments:
            if not (RAM_BASE <= addr and addr + len(blob) <= RAM_BASE + self.ram_bytes):
                raise ValueError(f"segment {addr:#x}+{len(blob):#x} outside the RAM")
            for i, b in enumerate(blob):
                a = addr + i
                mem.setdefault(a & ~3, bytearray(4))[a & 3] = b
        return {a: int.from_bytes(w, "little") for a, w in sorted(mem.items())}

    async def load(self, elf: Elf, wait_states: bool = False, clear: dict[int, int] | None = None) -> None:
        """Hold the core in reset, write the ELF's words (and zero ``clear``'s), set entry and tohost."""
        dut = self.dut
        dut.rst.value = 1
        await RisingEdge(dut.clk)
        words = dict(clear or {})
        words.update(self.image(elf))
        dut.ld_we.value = 1
        for a, w in words.items():
            dut.ld_addr.value = a
            dut.ld_wdata.value = w
            await RisingEdge(dut.clk)
        dut.ld_we.value = 0
        dut.boot_entry.value = elf.entry
        dut.tohost_addr.value = elf.symbols["tohost"]
        dut.wait_states.value = int(wait_states)
        await RisingEdge(dut.clk)

    async def run(self, max_cycles: int) -> RunResult:
        """Release reset and run until tohost is written or max_cycles pass."""
        dut = self.dut
        dut.rst.value = 0
        hit = RisingEdge(dut.tohost_hit)
        await First(hit, Timer(max_cycles * CLK_NS, unit="ns"))
        await ReadOnly()
        done = int(dut.tohost_hit.value) == 1
        result = RunResult(int(dut.tohost_value.value) if done else None,
                           int(dut.cycles.value), int(dut.instret.value))
        await RisingEdge(dut.clk)
        dut.rst.value = 1
        return result

    async def read_words(self, addr: int, count: int) -> list[int]:
        """Read RAM words through the load port (core held in reset)."""
        dut = self.dut
        dut.rst.value = 1
        out = []
        for i in range(count):
            dut.ld_addr.value = addr + 4 * i
            await RisingEdge(dut.clk)  # ld_rdata <= ram[ld_addr] at this edge
            await ReadOnly()
            out.append(int(dut.ld_rdata.value))
            await Timer(1, unit="ns")
        return out

    async def signature(self, elf: Elf) -> list[int]:
        b, e = elf.symbols["begin_signature"], elf.symbols["end_signature"]
        return await self.read_words(b, (e - b) // 4)
