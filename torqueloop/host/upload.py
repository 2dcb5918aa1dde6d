"""Firmware images for ``torqueloop upload``: ELF or raw binary -> bytes + CRC-32.

The link side of the upload (the boot ROM's receive protocol with CRC-32,
issue 4) does not exist yet: :data:`BOOTLOADER_AVAILABLE` is False and
``upload`` stops after checking the image, before it sends anything that
would leave the board waiting in the boot ROM.  What is here is the part
that does not depend on it: reading the image the build produces
(``build/firmware/servo/servo.elf`` or a flat ``.bin``), its loadable bytes
as one contiguous block from the lowest load address, and the CRC-32 the
bootloader will check.
"""

from __future__ import annotations

import struct
import zlib
from dataclasses import dataclass
from pathlib import Path

BOOTLOADER_AVAILABLE = False
NOT_AVAILABLE = ("upload is not available yet: the boot ROM bootloader (issue 4) is not built and "
                 "its upload protocol is not defined, so nothing was sent to the board. "
                 "Meanwhile the firmware goes into the FPGA image: docs/hardware.md, 'Building the FPGA image'.")

PT_LOAD = 1
EM_RISCV = 243


class ImageError(ValueError):
    pass


@dataclass(frozen=True)
class Image:
    load_addr: int
    data: bytes
    entry: int

    @property
    def crc32(self) -> int:
        return zlib.crc32(self.data) & 0xFFFFFFFF


def read_elf(raw: bytes) -> Image:
    """Loadable segments of a little-endian ELF32 RISC-V file, gaps filled with 0."""
    if raw[:4] != b"\x7fELF":
        raise ImageError("not an ELF file")
    if len(raw) < 52:
        raise ImageError(f"truncated ELF: {len(raw)} bytes, shorter than the 52-byte ELF32 header")
    if raw[4] != 1 or raw[5] != 1:
        raise ImageError("not a 32-bit little-endian ELF (the torqueloop CPU is RV32)")
    (e_type, e_machine, _v, e_entry, e_phoff, _sh, _fl, _eh, e_phentsize, e_phnum) = \
        struct.unpack_from("<HHIIIIIHHH", raw, 16)
    if e_machine != EM_RISCV:
        raise ImageError(f"ELF machine {e_machine}, not RISC-V ({EM_RISCV})")
    if e_phoff + e_phnum * e_phentsize > len(raw) or (e_phnum and e_phentsize < 32):
        raise ImageError("truncated ELF: the program headers run past the end of the file")
    segs = []
    for i in range(e_phnum):
        p_type, p_offset, _va, p_paddr, p_filesz, _memsz, _f, _a = \
            struct.unpack_from("<IIIIIIII", raw, e_phoff + i * e_phentsize)
        if p_type == PT_LOAD and p_filesz:
            if p_offset + p_filesz > len(raw):
                raise ImageError("truncated ELF: a segment runs past the end of the file")
            segs.append((p_paddr, raw[p_offset:p_offset + p_filesz]))
    if not segs:
        raise ImageError("ELF has no loadable segment")
    segs.sort()
    base = segs[0][0]
    out = bytearray()
    for addr, data in segs:
        if addr - base < len(out):
            raise ImageError(f"overlapping segments at 0x{addr:08x}")
        out += bytes(addr - base - len(out)) + data
    return Image(base, bytes(out), e_entry)


def read_image(path: str | Path, load_addr: int = 0) -> Image:
    p = Path(path)
    raw = p.read_bytes()
    if raw[:4] == b"\x7fELF":
        return read_elf(raw)
    if not raw:
        raise ImageError(f"{p}: empty file")
    return Image(load_addr, raw, load_addr)
