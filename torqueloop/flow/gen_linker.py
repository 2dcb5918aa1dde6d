# SPDX-License-Identifier: MIT
"""firmware/common/link.ld from the memory map (torqueloop/spec/regmap.toml),
and tb/cpu/progs/link.ld, the CPU test programs' script; written and checked
by ``python -m torqueloop.flow.generate [--check]``.

Firmware images run from RAM (loaded by RAM_INIT in simulation or on the
FPGA, later by the bootloader): code, constants, data, bss and stack all in
the RAM region; the boot ROM region is left to the boot code.
"""

from __future__ import annotations

from torqueloop.spec import bootproto
from torqueloop.spec.regmap import RegMap, load

STACK_BYTES = 4096


def linker_script(rm: RegMap | None = None) -> str:
    rm = rm or load()
    ram = rm.region("RAM")
    rom = rm.region("BOOT_ROM")
    return f"""/* Generated from torqueloop/spec/regmap.toml by torqueloop.flow.generate - do not edit. */
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

/* The firmware image header crt0.S puts after its first jump (torqueloop/spec/bootproto.py). */
__tl_image_magic = 0x{bootproto.IMAGE_MAGIC:08X};
__tl_image_map_version = {rm.version};
"""



def cpu_test_linker_script(rm: RegMap | None = None) -> str:
    """The CPU test programs of tb/cpu (run on cpu_sim_top and the ISS):
    everything in RAM, entry _start, and the tohost / begin_signature /
    end_signature symbols of the riscv-tests conventions run_elf.py reads."""
    rm = rm or load()
    ram = rm.region("RAM")
    return f"""/* Generated from torqueloop/spec/regmap.toml by torqueloop.flow.generate - do not edit. */
/* Test programs of tb/cpu: everything in the RAM of the SoC memory map, entry _start.
   tohost and the signature symbols follow the riscv-tests / riscv-arch-test
   conventions run_elf.py reads. */
OUTPUT_ARCH(riscv)
ENTRY(_start)
MEMORY {{ RAM (rwx) : ORIGIN = 0x{ram.base:08X}, LENGTH = 0x{ram.size:X} }}
SECTIONS
{{
  .text : {{ *(.text.init) *(.text .text.*) }} > RAM
  .rodata : {{ *(.rodata .rodata.* .srodata .srodata.*) }} > RAM
  .data : {{ *(.data .data.* .sdata .sdata.*) }} > RAM
  .bss : {{ *(.bss .bss.* .sbss .sbss.* COMMON) }} > RAM
  .signature : ALIGN(16) {{ begin_signature = .; *(.signature) end_signature = .; }} > RAM
  .tohost : ALIGN(64) {{ *(.tohost) }} > RAM
  __stack_top = ORIGIN(RAM) + LENGTH(RAM);
}}
"""


OUTPUTS = {"firmware/common/link.ld": linker_script, "tb/cpu/progs/link.ld": cpu_test_linker_script}
