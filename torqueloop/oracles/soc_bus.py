# SPDX-License-Identifier: MIT
"""Reference model of the SoC bus as software sees it, written from the
memory map (torqueloop/spec/regs.py, generated from torqueloop/spec/regmap.toml), not
from the RTL: which addresses answer, and what RAM holds."""

from __future__ import annotations

from dataclasses import dataclass, field

from torqueloop.spec import regs


@dataclass
class BusModel:
    """Address decode and memory contents of the SoC for both CPU buses."""

    ram_bytes: int = regs.RAM_SIZE
    rom: list[int] = field(default_factory=list)       # ROM words
    ram: bytearray = field(init=False)

    def __post_init__(self) -> None:
        self.ram = bytearray(self.ram_bytes)
        self._reg_words = {r.addr for r in regs.REGISTERS}

    # --- decode -------------------------------------------------------------------------
    def in_rom(self, addr: int) -> bool:
        return regs.BOOT_ROM_BASE <= addr < regs.BOOT_ROM_BASE + regs.BOOT_ROM_SIZE

    def in_ram(self, addr: int) -> bool:
        return regs.RAM_BASE <= addr < regs.RAM_BASE + self.ram_bytes

    def is_register(self, addr: int) -> bool:
        return (addr & ~3) in self._reg_words

    def ibus_err(self, addr: int) -> bool:
        """Instruction fetch: only ROM and RAM are executable."""
        return not (self.in_rom(addr) or self.in_ram(addr))

    def dbus_err(self, addr: int, we: bool) -> bool:
        if self.in_rom(addr):
            return we
        return not (self.in_ram(addr) or self.is_register(addr))

    # --- memory ----------------------------------------------------------------------------
    def load_ram_words(self, words: list[int]) -> None:
        for i, w in enumerate(words[: self.ram_bytes // 4]):
            self.ram[4 * i: 4 * i + 4] = w.to_bytes(4, "little")

    def read_word(self, addr: int) -> int:
        a = addr & ~3
        if self.in_rom(a):
            i = (a - regs.BOOT_ROM_BASE) // 4
            return self.rom[i] if i < len(self.rom) else 0
        o = a - regs.RAM_BASE
        return int.from_bytes(self.ram[o: o + 4], "little")

    def write_ram(self, addr: int, wdata: int, be: int) -> None:
        o = (addr & ~3) - regs.RAM_BASE
        for lane in range(4):
            if be >> lane & 1:
                self.ram[o + lane] = (wdata >> (8 * lane)) & 0xFF
