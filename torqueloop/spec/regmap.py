# SPDX-License-Identifier: MIT
"""The SoC memory and register map: load ``regmap.toml`` (this folder, the
one source) and check it.

Python reads it here at import (:mod:`.regs` exposes the constants by name);
every other view - the Verilog include, the VHDL package, the C header and
the data sheet - is generated from it by :mod:`torqueloop.flow.gen_regmap`
(``python -m torqueloop.flow.generate``), and ``make lint`` fails when one
is stale.
"""

from __future__ import annotations

import tomllib
from dataclasses import dataclass
from pathlib import Path

from torqueloop.spec.refs import resolve

REGMAP_TOML = Path(__file__).resolve().with_name("regmap.toml")

ACCESS_TYPES = ("rw", "ro", "w1c", "wo")
PAGE_BYTES = 0x1000  # one peripheral block per 4 KiB page


@dataclass(frozen=True)
class BusField:
    """One field of a peripheral-bus bundle, at bits [lsb + width - 1 : lsb]."""

    name: str
    lsb: int
    width: int
    desc: str

    @property
    def msb(self) -> int:
        return self.lsb + self.width - 1


def _bundle(*fields: tuple[str, int, str]) -> tuple[BusField, ...]:
    out, lsb = [], 0
    for name, width, desc in fields:
        out.append(BusField(name, lsb, width, desc))
        lsb += width
    return tuple(out)


#: The SoC's peripheral bus: what tl_soc_fabric hands a block for one access
#: to its page (request) and what the block answers in the same cycle
#: (response; the fabric registers it and acknowledges).  LSB first.  Verilog
#: carries each bundle as one vector (`TL_BUS_REQ_<FIELD>_LSB/_MSB in
#: regmap.vh), VHDL as the records tl_bus_req_t / tl_bus_rsp_t (regmap_pkg.vhd).
BUS_REQ = _bundle(
    ("stb", 1, "one-cycle strobe: an access to this page starts now (once per access)"),
    ("we", 1, "the access is a write"),
    ("idx", (PAGE_BYTES // 4 - 1).bit_length(), "word index in the page (addr[11:2]; addr[1:0] is ignored)"),
    ("wmask", 32, "the bits a write changes: each byte enable repeated over its byte"),
    ("wbits", 32, "write data with the bits outside wmask cleared"),
)
BUS_RSP = _bundle(
    ("rdata", 32, "the addressed register's read value (0 for write-only bits)"),
    ("err", 1, "the index names no register of this block: the fabric answers with a bus error"),
)

@dataclass(frozen=True)
class Field:
    name: str
    msb: int
    lsb: int
    access: str
    reset: int
    desc: str
    volatile: bool = False
    values: tuple[tuple[str, int], ...] = ()   # named values of the field (keys, codes)

    @property
    def width(self) -> int:
        return self.msb - self.lsb + 1

    @property
    def mask(self) -> int:
        """The field's bits in the register word."""
        return ((1 << self.width) - 1) << self.lsb


@dataclass(frozen=True)
class Register:
    name: str
    offset: int
    desc: str
    fields: tuple[Field, ...]

    def _mask(self, *access: str) -> int:
        m = 0
        for f in self.fields:
            if f.access in access:
                m |= f.mask
        return m

    @property
    def reset(self) -> int:
        """Value read after reset (write-only fields read 0)."""
        return sum((f.reset << f.lsb) for f in self.fields if f.access != "wo")

    #: the bits of the fields of one access type
    rw_mask = property(lambda self: self._mask("rw"))
    ro_mask = property(lambda self: self._mask("ro"))
    w1c_mask = property(lambda self: self._mask("w1c"))
    wo_mask = property(lambda self: self._mask("wo"))

    @property
    def readable_mask(self) -> int:
        """Bits that can read non-zero."""
        return self._mask("rw", "ro", "w1c")

    @property
    def volatile_mask(self) -> int:
        """Bits hardware may change without a bus write."""
        return sum(f.mask for f in self.fields if f.volatile)


@dataclass(frozen=True)
class Block:
    """A peripheral page; ``name`` is the instance name (AXIS0), ``kind`` the
    layout's name (AXIS) shared by all instances."""

    name: str
    kind: str
    base: int
    desc: str
    registers: tuple[Register, ...]

    def reg(self, name: str) -> Register:
        return _named(self.registers, name, f"{self.name} has no register {name}")


@dataclass(frozen=True)
class Region:
    name: str
    base: int
    size: int
    desc: str


@dataclass(frozen=True)
class RegMap:
    name: str
    version: int
    clk_hz: int
    regions: tuple[Region, ...]
    blocks: tuple[Block, ...]

    def block(self, name: str) -> Block:
        return _named(self.blocks, name, f"no block {name}")

    def region(self, name: str) -> Region:
        return _named(self.regions, name, f"no region {name}")

    @property
    def kinds(self) -> dict[str, Block]:
        """One representative block per layout (AXIS0 for AXIS)."""
        out: dict[str, Block] = {}
        for b in self.blocks:
            out.setdefault(b.kind, b)
        return out

    def constants(self) -> dict[str, int]:
        """Every named number of the map, as the C header and the Verilog
        include name them: ``<REGION>_BASE/_SIZE``, ``<BLOCK>_BASE``,
        ``<BLOCK>_<REG>`` (absolute address), ``<KIND>_<REG>_OFS`` and
        ``<KIND>_<REG>_<FIELD>_POS/_MSK``."""
        out: dict[str, int] = {"REGMAP_VERSION": self.version, "CLK_HZ": self.clk_hz}
        for r in self.regions:
            out[f"{r.name}_BASE"] = r.base
            out[f"{r.name}_SIZE"] = r.size
        for b in self.blocks:
            out[f"{b.name}_BASE"] = b.base
            for r in b.registers:
                out[f"{b.name}_{r.name}"] = b.base + r.offset
        for kind, b in self.kinds.items():
            for r in b.registers:
                out[f"{kind}_{r.name}_OFS"] = r.offset
                for f in r.fields:
                    out[f"{kind}_{r.name}_{f.name}_POS"] = f.lsb
                    out[f"{kind}_{r.name}_{f.name}_MSK"] = f.mask
                    for k, v in f.values:
                        out[f"{kind}_{r.name}_{f.name}_{k}"] = v
        return out


def _named(items, name: str, missing: str):
    """The item called ``name``; KeyError(``missing``) if there is none."""
    found = next((x for x in items if x.name == name), None)
    if found is None:
        raise KeyError(missing)
    return found


class RegMapError(ValueError):
    pass


def _field(d: dict, where: str) -> Field:
    msb, lsb = d["bits"]
    f = Field(name=d["name"], msb=int(msb), lsb=int(lsb), access=d["access"],
              reset=int(resolve(d.get("reset", 0), f"{where}.{d.get('name', '?')}.reset")), desc=d.get("desc", ""),
              volatile=bool(d.get("volatile", False)),
              values=tuple((str(k), int(v)) for k, v in d.get("values", {}).items()))
    if f.access not in ACCESS_TYPES:
        raise RegMapError(f"{where}.{f.name}: access {f.access!r} not in {ACCESS_TYPES}")
    if not 0 <= f.lsb <= f.msb <= 31:
        raise RegMapError(f"{where}.{f.name}: bits [{f.msb}:{f.lsb}] outside a 32-bit word")
    if f.reset >> f.width:
        raise RegMapError(f"{where}.{f.name}: reset {f.reset:#x} does not fit {f.width} bits")
    for k, v in f.values:
        if not 0 <= v < (1 << f.width):
            raise RegMapError(f"{where}.{f.name}: value {k} = {v:#x} does not fit {f.width} bits")
    return f


def _register(d: dict, where: str) -> Register:
    name = d["name"]
    fields = tuple(_field(fd, f"{where}.{name}") for fd in d.get("field", []))
    r = Register(name=name, offset=int(d["offset"]), desc=d.get("desc", ""), fields=fields)
    if not fields:
        raise RegMapError(f"{where}.{name}: no fields")
    if r.offset % 4 or not 0 <= r.offset < PAGE_BYTES:
        raise RegMapError(f"{where}.{name}: offset {r.offset:#x} not a word inside the page")
    seen = 0
    names = set()
    for f in fields:
        if seen & f.mask:
            raise RegMapError(f"{where}.{name}.{f.name}: bits overlap another field")
        if f.name in names:
            raise RegMapError(f"{where}.{name}: field {f.name} twice")
        seen |= f.mask
        names.add(f.name)
    return r


def parse(data: dict) -> RegMap:
    """Build and check a RegMap from the parsed TOML."""
    meta = data["meta"]
    regions = tuple(Region(r["name"], int(r["base"]), int(r["size"]), r.get("desc", ""))
                    for r in data.get("region", []))
    blocks: list[Block] = []
    for b in data.get("block", []):
        regs = tuple(_register(rd, b["name"]) for rd in b.get("reg", []))
        offs = [r.offset for r in regs]
        if len(set(offs)) != len(offs):
            raise RegMapError(f"{b['name']}: two registers share an offset")
        if len({r.name for r in regs}) != len(regs):
            raise RegMapError(f"{b['name']}: two registers share a name")
        instances = b.get("instances") or [{"name": b["name"], "base": b["base"]}]
        for inst in instances:
            blocks.append(Block(name=inst["name"], kind=b["name"], base=int(inst["base"]),
                                desc=b.get("desc", ""), registers=regs))
    rm = RegMap(name=meta["name"], version=int(meta["version"]), clk_hz=int(resolve(meta["clk_hz"], "meta.clk_hz")),
                regions=regions, blocks=tuple(blocks))
    _check_layout(rm)
    return rm


def _check_layout(rm: RegMap) -> None:
    spans = sorted((r.base, r.base + r.size, r.name) for r in rm.regions)
    for (b0, e0, n0), (b1, _e1, n1) in zip(spans, spans[1:]):
        if b1 < e0:
            raise RegMapError(f"regions {n0} and {n1} overlap")
    for r in rm.regions:
        if r.size & (r.size - 1) or r.base % r.size:
            raise RegMapError(f"region {r.name}: size must be a power of two and base aligned to it")
    periph = rm.region("PERIPH")
    bases = [b.base for b in rm.blocks]
    if len(set(bases)) != len(bases):
        raise RegMapError("two blocks share a page")
    names = [b.name for b in rm.blocks]
    if len(set(names)) != len(names):
        raise RegMapError("two blocks share a name")
    for b in rm.blocks:
        if b.base % PAGE_BYTES or not periph.base <= b.base < periph.base + periph.size:
            raise RegMapError(f"block {b.name}: base {b.base:#x} is not a page inside PERIPH")
    # Values stated twice in the TOML (meta and a register's reset) must agree.
    for blk, reg, want in (("SYS", "VERSION", rm.version), ("SYS", "CLK_HZ", rm.clk_hz)):
        try:
            got = rm.block(blk).reg(reg).reset
        except KeyError:
            continue
        if got != want:
            raise RegMapError(f"{blk}.{reg} reset {got} differs from meta ({want})")


def load(path: Path = REGMAP_TOML) -> RegMap:
    with open(path, "rb") as f:
        return parse(tomllib.load(f))
