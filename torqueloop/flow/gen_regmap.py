# SPDX-License-Identifier: MIT
"""Generated views of the register map (torqueloop/spec/regmap.toml):

* ``rtl/soc/regmap.vh``                  Verilog `defines (included by every file that uses them)
* ``rtl/soc/regmap_pkg.vhd``             the same constants as a VHDL-2008 package (VHDL twins)
* ``firmware/include/torqueloop_regs.h`` C11 header for the firmware
* ``docs/registers.md``                  the data sheet

Python needs no generated module: :mod:`torqueloop.spec.regs` reads the TOML.
"""

from __future__ import annotations

from torqueloop.spec.regmap import ACCESS_TYPES, BUS_REQ, BUS_RSP, PAGE_BYTES, BusField, Field, RegMap, load

#: generated file (relative to the repo root) -> generator function name
OUTPUTS = {
    "rtl/soc/regmap.vh": "verilog_header",
    "rtl/soc/regmap_pkg.vhd": "vhdl_package",
    "firmware/include/torqueloop_regs.h": "c_header",
    "docs/registers.md": "markdown",
}


_BANNER = "Generated from torqueloop/spec/regmap.toml by torqueloop.flow.generate - do not edit."


def verilog_header(rm: RegMap) -> str:
    """`defines: region bases/sizes, page indices, per-register word index
    within the page (_IDX, for case on addr[11:2]), reset value and access
    masks, per-field LSB/MSB/WIDTH/RESET.  Offsets are per layout (kind), so
    both AXIS instances share one set of register macros.  The peripheral bus
    bundles are vectors with a _LSB/_MSB pair per field."""
    L = [f"// {_BANNER}", "// Every file that uses these names includes it (`include \"regmap.vh\"); the guard makes",
         "// a second include empty, so no file depends on the compile order.",
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
    L += ["", "// Peripheral bus bundles, tl_soc_fabric <-> every block (docs/soc.md, Bus)"]
    for bundle, fields in (("REQ", BUS_REQ), ("RSP", BUS_RSP)):
        L.append(f"`define TL_BUS_{bundle}_WIDTH {_bundle_width(fields)}")
        for f in fields:
            L.append(f"`define TL_BUS_{bundle}_{f.name.upper()}_LSB {f.lsb}")
            L.append(f"`define TL_BUS_{bundle}_{f.name.upper()}_MSB {f.msb}")
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
                for k, v in f.values:
                    L.append(f"`define {q}_{k} {f.width}'h{v:X}")
    L += ["", "`endif", ""]
    return "\n".join(L)


def vhdl_package(rm: RegMap) -> str:
    """VHDL-2008 package tl_regmap_pkg with the constants of regmap.vh:
    word index (_IDX), reset and access masks (std_logic_vector(31 downto 0)),
    field LSB/MSB/WIDTH (natural); and the peripheral bus bundles as the
    records tl_bus_req_t / tl_bus_rsp_t (GHDL names their flattened ports
    bus_req_<field>, which the equivalence proof packs into regmap.vh's vector)."""
    L = [f"-- {_BANNER}", "library ieee;", "use ieee.std_logic_1164.all;", "",
         "package tl_regmap_pkg is",
         f"    constant TL_REGMAP_VERSION : natural := {rm.version};",
         f"    constant TL_CLK_HZ : natural := {rm.clk_hz};",
         "    -- Peripheral bus bundles, tl_soc_fabric <-> every block (docs/soc.md, Bus)"]
    for bundle, fields in (("req", BUS_REQ), ("rsp", BUS_RSP)):
        L.append(f"    type tl_bus_{bundle}_t is record")
        for f in fields:
            typ = "std_logic" if f.width == 1 else f"std_logic_vector({f.width - 1} downto 0)"
            L.append(f"        {f.name} : {typ};  -- {f.desc}")
        L.append("    end record;")
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
                for k, v in f.values:
                    L.append(f'    constant {q}_{k} : std_logic_vector({f.width - 1} downto 0) := '
                             f'"{v:0{f.width}b}";')
    L += ["end package tl_regmap_pkg;", ""]
    return "\n".join(L)


def _bundle_width(fields: tuple[BusField, ...]) -> int:
    return fields[-1].msb + 1


def c_header(rm: RegMap) -> str:
    """C11 header (numbers also for assembly: GNU as reads the u suffix):
    TL_<BLOCK>_<REG> is the register as a volatile lvalue, _ADDR its address; per layout TL_<KIND>_<REG>_OFS its offset in the page
    and _<FIELD>_POS/_MSK the field (CMSIS naming)."""
    L = [f"/* {_BANNER} */", "#ifndef TORQUELOOP_REGS_H", "#define TORQUELOOP_REGS_H", "",
         "/* Assembly sources (.S) may include it too: the numbers only. */",
         "#ifndef __ASSEMBLER__",
         "#include <stdint.h>", "",
         "#define TL_REG32(addr) (*(volatile uint32_t *)(uintptr_t)(addr))",
         "#endif", "",
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
                for k, v in f.values:
                    L.append(f"#define {q}_{k} 0x{v:X}u")
    L += ["", "#endif /* TORQUELOOP_REGS_H */", ""]
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
                vals = "; ".join(f"{k} = `0x{v:X}`" for k, v in f.values)
                L.append(f"| {_bits(f)} | {f.name} | {f.access} | `0x{f.reset:X}` | {f.desc}{vol}"
                         f"{' (' + vals + ')' if vals else ''} |")
    L.append("")
    return "\n".join(L)


def generate(rm: RegMap | None = None) -> dict[str, str]:
    """Every generated file's path (from the repo root) and its text."""
    rm = rm or load()
    return {path: globals()[fn](rm) for path, fn in OUTPUTS.items()}
