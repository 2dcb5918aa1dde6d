# SPDX-License-Identifier: MIT
"""The register map's constants by name (``regs.AXIS0_CTRL``,
``regs.RAM_BASE``, ``regs.CLK_HZ`` ...), read from regmap.toml at import:
:meth:`torqueloop.spec.regmap.RegMap.constants` defines the names, the same
ones the C header and the Verilog include carry.  ``REGISTERS`` lists every
register with its absolute address, reset value and access masks.
"""

from __future__ import annotations

from dataclasses import dataclass

from torqueloop.spec.regmap import load


@dataclass(frozen=True)
class Reg:
    """One register: where it is, what it reads after reset, how each bit is written."""

    block: str
    name: str
    addr: int
    reset: int
    rw_mask: int
    ro_mask: int
    w1c_mask: int
    wo_mask: int
    volatile_mask: int


MAP = load()
globals().update(MAP.constants())

REGISTERS: tuple[Reg, ...] = tuple(
    Reg(b.name, r.name, b.base + r.offset, r.reset, r.rw_mask, r.ro_mask, r.w1c_mask, r.wo_mask,
        r.volatile_mask)
    for b in MAP.blocks for r in b.registers)


def __getattr__(name: str) -> int:
    raise AttributeError(f"the register map has no constant {name!r} (torqueloop/spec/regmap.toml)")
