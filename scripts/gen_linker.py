#!/usr/bin/env python3
"""Generate firmware/common/link.ld from the memory map (rtl/soc/regmap.toml).

    python scripts/gen_linker.py            # write it
    python scripts/gen_linker.py --check    # exit 1 if stale

Firmware images run from RAM (loaded by RAM_INIT in simulation or on the
FPGA, later by the bootloader): code, constants, data, bss and stack all in
the RAM region; the boot ROM region is left to the boot code.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(REPO))

from torqueloop import regmap  # noqa: E402

OUT = REPO / "firmware" / "common" / "link.ld"
STACK_BYTES = 4096


def linker_script(rm: regmap.RegMap | None = None) -> str:
    rm = rm or regmap.load()
    ram = rm.region("RAM")
    rom = rm.region("BOOT_ROM")
    return f"""/* Generated from rtl/soc/regmap.toml by scripts/gen_linker.py - do not edit. */
/* torqueloop firmware image: everything in RAM, entry _start at the RAM base. */
OUTPUT_ARCH(riscv)
ENTRY(_start)

MEMORY
{{
    BOOT_ROM (rx) : ORIGIN = 0x{rom.base:08X}, LENGTH = 0x{rom.size:X}
    RAM (rwx)     : ORIGIN = 0x{ram.base:08X}, LENGTH = 0x{ram.size:X}
}}

__stack_bytes = 0x{STACK_BYTES:X};

SECTIONS
{{
    .text : {{
        KEEP(*(.text.start))
        *(.text .text.*)
    }} > RAM

    .rodata : {{
        *(.rodata .rodata.* .srodata .srodata.*)
        . = ALIGN(4);
    }} > RAM

    .data : {{
        __data_start = .;
        *(.data .data.* .sdata .sdata.*)
        . = ALIGN(4);
        __data_end = .;
    }} > RAM

    .bss (NOLOAD) : {{
        __bss_start = .;
        *(.bss .bss.* .sbss .sbss.* COMMON)
        . = ALIGN(4);
        __bss_end = .;
    }} > RAM

    __stack_top = ORIGIN(RAM) + LENGTH(RAM);
    ASSERT(__bss_end + __stack_bytes <= __stack_top, "firmware: no room left for the stack")
    __global_pointer$ = __data_start + 0x800;
    __boot_rom_reset = ORIGIN(BOOT_ROM);
}}
"""


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--check", action="store_true")
    args = ap.parse_args(argv)
    text = linker_script()
    if args.check:
        if not OUT.exists() or OUT.read_text() != text:
            print(f"stale: {OUT.relative_to(REPO)} (run python scripts/gen_linker.py)")
            return 1
        return 0
    OUT.write_text(text)
    print(f"wrote {OUT.relative_to(REPO)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
