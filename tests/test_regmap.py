# SPDX-License-Identifier: MIT
"""The register map (torqueloop/spec/regmap.toml) and its generated views."""

from __future__ import annotations

import subprocess
import tomllib

import pytest

from torqueloop.flow.generate import products, stale
from torqueloop.flow.manifest import REPO_ROOT
from torqueloop.spec import regmap


def test_generated_files_are_up_to_date():
    """A stale generated file (rtl/soc/regmap.vh, a C header, the linker
    script, docs/registers.md, the .qsf ...) fails here:
    run `python -m torqueloop.flow.generate` and commit."""
    assert stale(products()) == []


def test_fixed_memory_map_matches_the_cpu_contract():
    rm = regmap.load()
    assert rm.region("BOOT_ROM").base == 0x0000_0000 and rm.region("BOOT_ROM").size == 65536
    assert rm.region("RAM").base == 0x8000_0000
    assert rm.region("PERIPH").base == 0x4000_0000
    t = rm.block("TIMER")
    assert t.base == 0x4000_0000
    assert [(r.name, r.offset) for r in t.registers[:4]] == [
        ("MTIME_LO", 0x0), ("MTIME_HI", 0x4), ("MTIMECMP_LO", 0x8), ("MTIMECMP_HI", 0xC)]


def test_python_module_agrees_with_the_source():
    from torqueloop.spec import regs
    rm = regmap.load()
    table = {(r.block, r.name): r for r in regs.REGISTERS}
    assert len(table) == sum(len(b.registers) for b in rm.blocks)
    for b in rm.blocks:
        for r in b.registers:
            g = table[(b.name, r.name)]
            assert g.addr == b.base + r.offset
            assert g.reset == r.reset
            assert g.rw_mask | g.ro_mask | g.w1c_mask | g.wo_mask == sum(f.mask for f in r.fields)


def test_c_header_compiles_and_places_registers(tmp_path):
    """The C header is valid C11 and its addresses are the map's (checked by the
    compiler with static asserts, freestanding, as the firmware builds)."""
    rm = regmap.load()
    checks = []
    for b in rm.blocks:
        for r in b.registers:
            checks.append(f"_Static_assert(TL_{b.name}_{r.name}_ADDR == {b.base + r.offset:#x}u, \"{b.name}.{r.name}\");")
    src = tmp_path / "t.c"
    src.write_text('#include "torqueloop_regs.h"\n' + "\n".join(checks)
                   + "\nvoid f(void) { TL_GPIO_LEDR = TL_GPIO_LEDR_LEDR_MSK; }\n")
    for cc in ("gcc", "riscv64-unknown-elf-gcc"):
        proc = subprocess.run([cc, "-std=c11", "-ffreestanding", "-Wall", "-Wextra", "-Werror", "-c",
                               "-I", str(REPO_ROOT / "firmware" / "include"), str(src), "-o",
                               str(tmp_path / f"{cc}.o")], capture_output=True, text=True)
        assert proc.returncode == 0, proc.stderr


def _load_text(text: str) -> regmap.RegMap:
    return regmap.parse(tomllib.loads(text))


_BASE = """
[meta]
name = "t"
version = 1
clk_hz = 1
[[region]]
name = "PERIPH"
base = 0x4000_0000
size = 0x8000
"""


def test_version_register_follows_meta():
    text = regmap.REGMAP_TOML.read_text()
    assert "version = 1 " in text
    with pytest.raises(regmap.RegMapError, match="VERSION"):
        _load_text(text.replace("version = 1 ", "version = 2 ", 1))


@pytest.mark.parametrize("bad, why", [
    ('[[block]]\nname="A"\nbase=0x4000_0000\n[[block.reg]]\nname="R"\noffset=0\n'
     'field=[{name="X",bits=[3,0],access="rw"},{name="Y",bits=[4,3],access="rw"}]', "overlap"),
    ('[[block]]\nname="A"\nbase=0x4000_0000\n[[block.reg]]\nname="R"\noffset=2\n'
     'field=[{name="X",bits=[3,0],access="rw"}]', "offset"),
    ('[[block]]\nname="A"\nbase=0x4000_0000\n[[block.reg]]\nname="R"\noffset=0\n'
     'field=[{name="X",bits=[3,0],access="rw",reset=16}]', "fit"),
    ('[[block]]\nname="A"\nbase=0x4000_0000\n[[block.reg]]\nname="R"\noffset=0\n'
     'field=[{name="X",bits=[3,0],access="rx"}]', "access"),
    ('[[block]]\nname="A"\nbase=0x5000_0000\n[[block.reg]]\nname="R"\noffset=0\n'
     'field=[{name="X",bits=[3,0],access="rw"}]', "PERIPH"),
    ('[[block]]\nname="A"\nbase=0x4000_0000\n[[block.reg]]\nname="R"\noffset=0\n'
     'field=[{name="X",bits=[3,0],access="rw"}]\n[[block.reg]]\nname="S"\noffset=0\n'
     'field=[{name="X",bits=[3,0],access="rw"}]', "offset"),
])
def test_checker_rejects_broken_maps(bad, why):
    with pytest.raises(regmap.RegMapError, match=why):
        _load_text(_BASE + bad)


def test_ram_fits_the_device_with_room_to_spare():
    """64 KiB is 64 of the 5CEBA4's 308 M10K blocks (1 KiB of data each in x32 mode)."""
    ram = regmap.load().region("RAM").size
    assert ram // 1024 <= 308 // 2


def test_bus_oracle_decodes_the_map():
    """torqueloop/oracles/soc_bus.py (the benches' decode oracle) against the map:
    every register answers, the word after each block's last register and
    the unused pages do not, and execution is limited to ROM and RAM."""
    from torqueloop.oracles.soc_bus import BusModel
    rm = regmap.load()
    m = BusModel()
    for b in rm.blocks:
        for r in b.registers:
            assert not m.dbus_err(b.base + r.offset, we=False)
            assert m.ibus_err(b.base + r.offset)
        last = max(r.offset for r in b.registers)
        assert m.dbus_err(b.base + last + 4, we=False)
    used = {b.base for b in rm.blocks}
    periph = rm.region("PERIPH")
    for page in range(periph.base, periph.base + periph.size, regmap.PAGE_BYTES):
        if page not in used:
            assert m.dbus_err(page, we=False), f"unused page {page:#x} must be an error"
    assert m.dbus_err(regmap.load().region("BOOT_ROM").base, we=True), "ROM write"
    assert not m.ibus_err(0) and not m.ibus_err(0x8000_0000) and m.ibus_err(0x8000_0000 + m.ram_bytes)
