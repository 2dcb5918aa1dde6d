# SPDX-License-Identifier: MIT
"""A model of the board's configuration flash (the DE0-CV's EPCS64) at the
level of its serial command set, for the simulated board (``simboard.py``
calls it once per byte the firmware clocks) and the SoC's test benches.

What it models, from the EPCS command set (protocol.toml ``[store]``):
READ (any length, from any address), WRITE ENABLE (sets the latch every
write needs; a write clears it), READ STATUS (WIP while a write runs, WEL),
PAGE PROGRAM (up to a page, the address wrapping inside its page; bits only
go from 1 to 0: the new byte is ANDed into the old), SECTOR ERASE (the sector
to 0xFF).  A write starts when chip select rises after whole bytes, and runs
for ``program_s`` / ``erase_s`` of the model's time, which moves on by one
byte time per byte clocked; while it runs only READ STATUS is answered.

Power loss: :meth:`cut` names the write (by its index since power-up, a
running count of erases and page programs) during or after which the power
fails.  An erase cut in its middle leaves the first half of the sector
erased and the rest as it was, a program cut in its middle the first half of
its bytes programmed; from then on the chip answers nothing (the line reads
low: never busy) until :meth:`power_on`.

``path``: the memory is kept in that file (sectors that are not blank), so
a simulated board started again with the same file finds what was written,
as after a power cycle.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from torqueloop.spec.protocol import STORE

FLASH_BYTES = STORE["flash_bytes"]
SECTOR_BYTES = STORE["sector_bytes"]
PAGE_BYTES = STORE["page_bytes"]
WIP, WEL = STORE["status_wip"], STORE["status_wel"]
OP_READ, OP_WREN, OP_RDSR = STORE["op_read"], STORE["op_write_enable"], STORE["op_read_status"]
OP_PP, OP_SE = STORE["op_page_program"], STORE["op_sector_erase"]
#: the simulated board's serial clock: a quarter of the 50 MHz system clock (simboard_hal.c)
SPI_HZ = 12_500_000


@dataclass
class Cut:
    write: int          # index of the write (erase or page program) since power-up
    during: bool        # in its middle (True) or right after it (False)


class Epcs:
    def __init__(self, path: Path | str | None = None, *, program_s: float = STORE["page_program_us"] / 1e6,
                 erase_s: float = STORE["sector_erase_us"] / 1e6, spi_hz: float = SPI_HZ) -> None:
        self.mem = bytearray(b"\xff" * FLASH_BYTES)
        self.path = Path(path) if path else None
        self.program_s, self.erase_s, self.byte_s = program_s, erase_s, 8.0 / spi_hz
        self.t = 0.0
        self.writes = 0                  # erases and page programs started since power-up
        self.log: list[tuple[str, int]] = []   # (op, address) of every write, for tests
        self._cut: Cut | None = None
        self.powered = True
        self._busy_until = 0.0
        self._wel = False
        self._sel = False
        self._cmd = bytearray()
        if self.path and self.path.exists():
            self._load()

    # ---- the serial port ---------------------------------------------------------
    def select(self, on: bool) -> None:
        if not self.powered:
            return
        if on and not self._sel:
            self._cmd = bytearray()
        elif not on and self._sel:
            self._execute()
        self._sel = on

    def xfer(self, out: int) -> int:
        """One byte clocked while selected: ``out`` in, the byte the chip drives back."""
        back = self.peek()
        self.t += self.byte_s
        if self.powered and self._sel:
            self._cmd.append(out & 0xFF)
        return back

    def peek(self) -> int:
        """The byte the chip drives during the next byte clocked (it depends only on the
        bytes before it: the pin-level adapter drives it bit by bit as the byte is clocked)."""
        if not self.powered:
            return 0x00
        c = self._cmd
        if not self._sel or not c:
            return 0xFF
        if c[0] == OP_RDSR:
            return self.status()
        if not self.busy() and c[0] == OP_READ and len(c) >= 4:
            addr = (c[1] << 16 | c[2] << 8 | c[3]) + len(c) - 4
            return self.mem[addr % FLASH_BYTES]
        return 0xFF

    def status(self) -> int:
        return (WIP if self.busy() else 0) | (WEL if self._wel else 0)

    def busy(self) -> bool:
        return self.t < self._busy_until

    # ---- power -----------------------------------------------------------------------
    def cut(self, write: int, during: bool) -> None:
        """Lose power during (or right after) write number ``write`` (0 = the first after power-up)."""
        self._cut = Cut(write, during)

    def power_on(self) -> None:
        """Power back: the memory as it was left, the chip idle."""
        self.powered, self._cut = True, None
        self._busy_until, self._wel, self._sel, self.writes = 0.0, False, False, 0

    # ---- inside ----------------------------------------------------------------------
    def _execute(self) -> None:
        c = bytes(self._cmd)
        if not c or self.busy() and c[0] != OP_RDSR:
            return
        if c == bytes([OP_WREN]):
            self._wel = True
            return
        if c[0] not in (OP_PP, OP_SE) or not self._wel:
            return
        addr = c[1] << 16 | c[2] << 8 | c[3] if len(c) >= 4 else -1
        if addr < 0 or (c[0] == OP_SE and len(c) != 4) or (c[0] == OP_PP and len(c) < 5):
            return
        self._wel = False
        cut = self._cut if self._cut and self._cut.write == self.writes else None
        self.writes += 1
        if c[0] == OP_SE:
            base = addr - addr % SECTOR_BYTES
            n = SECTOR_BYTES // 2 if cut and cut.during else SECTOR_BYTES
            self.mem[base:base + n] = b"\xff" * n
            self._busy_until = self.t + self.erase_s
            self.log.append(("erase", base))
        else:
            data = c[4:]
            page = addr - addr % PAGE_BYTES
            n = len(data) // 2 if cut and cut.during else len(data)
            for i, d in enumerate(data[:n]):
                a = page + (addr + i) % PAGE_BYTES      # the address wraps inside its page
                self.mem[a] &= d
            self._busy_until = self.t + self.program_s
            self.log.append(("program", addr))
        if cut:
            self.powered = False
            self._busy_until = 0.0
        self._save()

    def _save(self) -> None:
        if not self.path:
            return
        blank = b"\xff" * SECTOR_BYTES
        out = bytearray()
        for base in range(0, FLASH_BYTES, SECTOR_BYTES):
            sec = self.mem[base:base + SECTOR_BYTES]
            if sec != blank:
                out += base.to_bytes(4, "little") + sec
        tmp = self.path.with_suffix(self.path.suffix + ".tmp")
        tmp.write_bytes(bytes(out))
        tmp.replace(self.path)

    def _load(self) -> None:
        data = self.path.read_bytes()
        step = 4 + SECTOR_BYTES
        if len(data) % step:
            raise ValueError(f"{self.path}: not a flash image of this model ({len(data)} bytes)")
        for i in range(0, len(data), step):
            base = int.from_bytes(data[i:i + 4], "little")
            if base % SECTOR_BYTES or base >= FLASH_BYTES:
                raise ValueError(f"{self.path}: sector address 0x{base:x} out of the flash")
            self.mem[base:base + SECTOR_BYTES] = data[i + 4:i + step]
