"""The SoC memory and register map: load rtl/soc/regmap.toml, check it, and
generate every derived view from it.

One source (regmap.toml), four generated files:

* ``rtl/soc/regmap.vh``              Verilog `defines (listed first in the SoC cores' sources)
* ``rtl/soc/regmap_pkg.vhd``         the same constants as a VHDL-2008 package (VHDL twins)
* ``firmware/include/torqueloop_regs.h``  C11 header for the firmware
* ``torqueloop/regs.py``             Python constants and register table (tests, host tools)
* ``docs/registers.md``              the data sheet

``scripts/gen_regmap.py`` writes them; ``tests/test_regmap.py`` regenerates
and diffs, so a stale generated file fails ``make unit``.
"""

from __future__ import annotations

import tomllib
from dataclasses import dataclass
from pathlib import Path

from torqueloop.hdl import REPO_ROOT

REGMAP_TOML = REPO_ROOT / "rtl" / "soc" / "regmap.toml"

ACCESS_TYPES = ("rw", "ro", "w1c", "wo")
PAGE_BYTES = 0x1000  # one peripheral block per 4 KiB page

#: generated file -> generator function name (relative to the repo root)
OUTPUTS = {
    "rtl/soc/regmap.vh": "verilog_header",
    "rtl/soc/regmap_pkg.vhd": "vhdl_package",
    "firmware/include/torqueloop_regs.h": "c_header",
    "torqueloop/regs.py": "python_module",
    "docs/registers.md": "markdown",
}


@dataclass(frozen=True)
class Field:
    name: str
    msb: int
    lsb: int
    access: str
    reset: int
    desc: str
    volatile: bool = False

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

    @property
    def rw_mask(self) -> int:
        return self._mask("rw")

    @property
    def ro_mask(self) -> int:
        return self._mask("ro")

    @property
    def w1c_mask(self) -> int:
        return self._mask("w1c")

    @property
    def wo_mask(self) -> int:
        return self._mask("wo")

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
        for r in self.registers:
            if r.name == name:
                return r
        raise KeyError(f"{self.name} has no register {name}")


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
        for b in self.blocks:
            if b.name == name:
                return b
        raise KeyError(f"no block {name}")

    def region(self, name: str) -> Region:
        for r in self.regions:
            if r.name == name:
                return r
        raise KeyError(f"no region {name}")

    @property
    def kinds(self) -> dict[str, Block]:
        """One representative block per layout (AXIS0 for AXIS)."""
        out: dict[str, Block] = {}
        for b in self.blocks:
            out.setdefault(b.kind, b)
        return out


class RegMapError(ValueError):
    pass


def _field(d: dict, where: str) -> Field:
    msb, lsb = d["bits"]
    f = Field(name=d["name"], msb=int(msb), lsb=int(lsb), access=d["access"],
              reset=int(d.get("reset", 0)), desc=d.get("desc", ""),
              volatile=bool(d.get("volatile", False)))
    if f.access not in ACCESS_TYPES:
        raise RegMapError(f"{where}.{f.name}: access {f.access!r} not in {ACCESS_TYPES}")
    if not 0 <= f.lsb <= f.msb <= 31:
        raise RegMapError(f"{where}.{f.name}: bits [{f.msb}:{f.lsb}] outside a 32-bit word")
    if f.reset >> f.width:
        raise RegMapError(f"{where}.{f.name}: reset {f.reset:#x} does not fit {f.width} bits")
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
    rm = RegMap(name=meta["name"], version=int(meta["version"]), clk_hz=int(meta["clk_hz"]),
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


# --- generators -----------------------------------------------------------------------

_BANNER = "Generated from rtl/soc/regmap.toml by scripts/gen_regmap.py - do not edit."


def verilog_header(rm: RegMap) -> str:
    """`defines: region bases/sizes, page indices, per-register word index
    within the page (_IDX, for case on addr[11:2]), reset value and access
    masks, per-field LSB/MSB/WIDTH/RESET.  Offsets are per layout (kind), so
    both AXIS instances share one set of register macros."""
    L = [f"// {_BANNER}", "// Listed first in every SoC core's source list (macros are global).",
         "`ifndef TL_REGMAP_VH", "`define TL_REGMAP_VH", "",
         f"`define TL_REGMAP_VERSION 32'd{rm.version}",
         f"`define TL_CLK_HZ 32'd{rm.clk_hz}", ""]
    for r in rm.regions:
        L.append(f"`define TL_{r.name}_BASE 32'h{r.base:08X}")
        L.append(f"`define TL_{r.name}_SIZE 32'h{r.size:08X}")
    L.append("")
    periph = rm.region("PERIPH")
    for b in rm.blocks:
        L.append(f"`define TL_{b.name}_BASE 32'h{b.base:08X}")
        L.append(f"`define TL_{b.name}_PAGE {(b.base - periph.base) // PAGE_BYTES}")
    for kind, b in rm.kinds.items():
        L.append("")
        L.append(f"// {kind}")
        for r in b.registers:
            p = f"TL_{kind}_{r.name}"
            L.append(f"`define {p}_IDX 10'd{r.offset // 4}")
            L.append(f"`define {p}_RESET 32'h{r.reset:08X}")
            for acc in ACCESS_TYPES:
                L.append(f"`define {p}_{acc.upper()}_MASK 32'h{getattr(r, acc + '_mask'):08X}")
            for f in r.fields:
                q = f"{p}_{f.name}"
                L.append(f"`define {q}_LSB {f.lsb}")
                L.append(f"`define {q}_MSB {f.msb}")
                L.append(f"`define {q}_WIDTH {f.width}")
                L.append(f"`define {q}_RESET {f.width}'h{f.reset:X}")
    L += ["", "`endif", ""]
    return "\n".join(L)


def vhdl_package(rm: RegMap) -> str:
    """VHDL-2008 package tl_regmap_pkg with the constants of regmap.vh:
    word index (_IDX), reset and access masks (std_logic_vector(31 downto 0)),
    field LSB/MSB/WIDTH (natural)."""
    L = [f"-- {_BANNER}", "library ieee;", "use ieee.std_logic_1164.all;", "",
         "package tl_regmap_pkg is",
         f"    constant TL_REGMAP_VERSION : natural := {rm.version};",
         f"    constant TL_CLK_HZ : natural := {rm.clk_hz};"]
    for kind, b in rm.kinds.items():
        L.append(f"    -- {kind}")
        for r in b.registers:
            p = f"TL_{kind}_{r.name}"
            L.append(f"    constant {p}_IDX : natural := {r.offset // 4};")
            L.append(f'    constant {p}_RESET : std_logic_vector(31 downto 0) := x"{r.reset:08X}";')
            for acc in ACCESS_TYPES:
                L.append(f'    constant {p}_{acc.upper()}_MASK : std_logic_vector(31 downto 0) := '
                         f'x"{getattr(r, acc + "_mask"):08X}";')
            for f in r.fields:
                q = f"{p}_{f.name}"
                L.append(f"    constant {q}_LSB : natural := {f.lsb};")
                L.append(f"    constant {q}_MSB : natural := {f.msb};")
                L.append(f"    constant {q}_WIDTH : natural := {f.width};")
    L += ["end package tl_regmap_pkg;", ""]
    return "\n".join(L)


def c_header(rm: RegMap) -> str:
    """C11 header: TL_<BLOCK>_<REG> is the register as a volatile lvalue,
    _ADDR its address; per layout TL_<KIND>_<REG>_OFS its offset in the page
    and _<FIELD>_POS/_MSK the field (CMSIS naming)."""
    L = [f"/* {_BANNER} */", "#ifndef TORQUELOOP_REGS_H", "#define TORQUELOOP_REGS_H", "",
         "#include <stdint.h>", "",
         "#define TL_REG32(addr) (*(volatile uint32_t *)(uintptr_t)(addr))", "",
         f"#define TL_REGMAP_VERSION {rm.version}u",
         f"#define TL_CLK_HZ {rm.clk_hz}u", ""]
    for r in rm.regions:
        L.append(f"#define TL_{r.name}_BASE 0x{r.base:08X}u")
        L.append(f"#define TL_{r.name}_SIZE 0x{r.size:08X}u")
    for b in rm.blocks:
        L += ["", f"/* {b.name}: {b.desc.split('. ')[0].rstrip('.')}. */",
              f"#define TL_{b.name}_BASE 0x{b.base:08X}u"]
        for r in b.registers:
            p = f"TL_{b.name}_{r.name}"
            L.append(f"#define {p}_ADDR 0x{b.base + r.offset:08X}u")
            L.append(f"#define {p} TL_REG32({p}_ADDR)")
            L.append(f"#define {p}_RESET 0x{r.reset:08X}u")
    for kind, b in rm.kinds.items():
        L += ["", f"/* {kind} register offsets in the page (index several instances: base + _OFS) and fields */"]
        for r in b.registers:
            L.append(f"#define TL_{kind}_{r.name}_OFS 0x{r.offset:03X}u")
            for f in r.fields:
                q = f"TL_{kind}_{r.name}_{f.name}"
                L.append(f"#define {q}_POS {f.lsb}u")
                L.append(f"#define {q}_MSK 0x{f.mask:08X}u")
    L += ["", "#endif /* TORQUELOOP_REGS_H */", ""]
    return "\n".join(L)


def python_module(rm: RegMap) -> str:
    """Standalone Python module: constants and a table of every register
    (absolute address, reset, access masks) for tests and host tools."""
    L = [f'"""{_BANNER}"""', "", "from __future__ import annotations", "",
         "from dataclasses import dataclass", "", "",
         "@dataclass(frozen=True)", "class Reg:",
         '    """One register: where it is, what it reads after reset, how each bit is written."""',
         "", "    block: str", "    name: str", "    addr: int", "    reset: int",
         "    rw_mask: int", "    ro_mask: int", "    w1c_mask: int", "    wo_mask: int",
         "    volatile_mask: int", "", "",
         f"REGMAP_VERSION = {rm.version}", f"CLK_HZ = {rm.clk_hz}", ""]
    for r in rm.regions:
        L.append(f"{r.name}_BASE = 0x{r.base:08X}")
        L.append(f"{r.name}_SIZE = 0x{r.size:08X}")
    for b in rm.blocks:
        L += ["", f"{b.name}_BASE = 0x{b.base:08X}"]
        for r in b.registers:
            L.append(f"{b.name}_{r.name} = 0x{b.base + r.offset:08X}")
    for kind, b in rm.kinds.items():
        L.append("")
        for r in b.registers:
            L.append(f"{kind}_{r.name}_OFS = 0x{r.offset:03X}")
            for f in r.fields:
                L.append(f"{kind}_{r.name}_{f.name}_POS = {f.lsb}")
                L.append(f"{kind}_{r.name}_{f.name}_MSK = 0x{f.mask:08X}")
    L += ["", "REGISTERS: tuple[Reg, ...] = ("]
    for b in rm.blocks:
        for r in b.registers:
            L.append(f"    Reg({b.name!r}, {r.name!r}, 0x{b.base + r.offset:08X}, 0x{r.reset:08X}, "
                     f"0x{r.rw_mask:08X}, 0x{r.ro_mask:08X}, 0x{r.w1c_mask:08X}, "
                     f"0x{r.wo_mask:08X}, 0x{r.volatile_mask:08X}),")
    L += [")", ""]
    return "\n".join(L)


def _bits(f: Field) -> str:
    return f"{f.msb}" if f.msb == f.lsb else f"{f.msb}:{f.lsb}"


def markdown(rm: RegMap) -> str:
    L = ["# torqueloop SoC registers", "", f"<!-- {_BANNER} -->", "",
         f"Register map version {rm.version}; clock {rm.clk_hz} Hz. "
         "Access types: `rw` read/write, `ro` read-only (writes ignored), "
         "`w1c` set by hardware, write 1 to clear, `wo` write-only (reads 0). "
         "*volatile*: hardware changes the field on its own. "
         "Every register honours byte enables. An address not listed here answers with a bus error.",
         "", "## Memory map", "", "| region | base | size | description |", "|---|---|---|---|"]
    for r in rm.regions:
        L.append(f"| {r.name} | `0x{r.base:08X}` | {r.size // 1024} KiB | {r.desc} |")
    L += ["", "## Peripheral pages", "", "| block | base | layout |", "|---|---|---|"]
    for b in rm.blocks:
        L.append(f"| [{b.name}](#{b.kind.lower()}) | `0x{b.base:08X}` | {b.kind} |")
    for kind, b in rm.kinds.items():
        insts = [x for x in rm.blocks if x.kind == kind]
        where = ", ".join(f"{x.name} at `0x{x.base:08X}`" for x in insts)
        L += ["", f"## {kind}", "", f"{where}.", "", b.desc, "",
              "| offset | register | reset | description |", "|---|---|---|---|"]
        for r in b.registers:
            L.append(f"| `+0x{r.offset:03X}` | [{r.name}](#{kind.lower()}_{r.name.lower()}) "
                     f"| `0x{r.reset:08X}` | {r.desc} |")
        for r in b.registers:
            L += ["", f"### {kind}_{r.name}", "", f"Offset `+0x{r.offset:03X}`. {r.desc}", "",
                  "| bits | field | access | reset | description |", "|---|---|---|---|---|"]
            for f in sorted(r.fields, key=lambda f: -f.lsb):
                vol = " *(volatile)*" if f.volatile else ""
                L.append(f"| {_bits(f)} | {f.name} | {f.access} | `0x{f.reset:X}` | {f.desc}{vol} |")
    L.append("")
    return "\n".join(L)


def generate(rm: RegMap | None = None) -> dict[str, str]:
    """Every generated file's path (from the repo root) and its text."""
    rm = rm or load()
    return {path: globals()[fn](rm) for path, fn in OUTPUTS.items()}
