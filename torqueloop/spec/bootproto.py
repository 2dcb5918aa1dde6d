# SPDX-License-Identifier: MIT
"""Host side of the boot-ROM upload (docs/bootloader.md): frame, CRC-32,
replies, ROM layout, and sending an image over pyserial ``serial_for_url``
(a serial port such as ``/dev/ttyUSB0`` or the RN-XV's ``socket://host:2000``).

This module is the single definition of the upload protocol: the bootloader
(firmware/boot/boot.c) is compiled against ``boot_proto.h``, which
:func:`torqueloop.flow.boot_image.boot_proto_header` generates from the constants below, and the cocotb benches
build their frames with :func:`encode_frame`, the same code the host tool uses.
"""

from __future__ import annotations

import enum
import struct
import zlib
from pathlib import Path

from torqueloop.spec import auth, regs

# --- protocol constants (docs/bootloader.md) -----------------------------------

SYNC = bytes([0xA5, 0x5A, 0xB0, 0x07])   # non-ASCII, no 0x00: neither RN-XV text nor a COBS delimiter
VERSION = 2                              # 2: the image is followed by its MAC (docs/security.md)
HEADER_FMT = "<BBHIII"                   # version, 0, 0, load address, length, image CRC-32
HEADER_BYTES = struct.calcsize(HEADER_FMT)        # 16; the header's own CRC-32 follows
FRAME_OVERHEAD = len(SYNC) + HEADER_BYTES + 4     # 24 bytes before the image
TAG_BYTES = auth.UPLOAD_TAG_BYTES        # after the image: HMAC-SHA-256(key, "TLUP" | header | image)
LOAD_ADDR = regs.RAM_BASE                # images are RAM-linked; entry = load address
BOOT_STACK_BYTES = 1024                  # the bootloader's stack at the top of RAM (HMAC-SHA-256 needs ~500 B)
MAX_IMAGE_BYTES = regs.RAM_SIZE - BOOT_STACK_BYTES
WINDOW_MS = 500                          # listen after reset
GAP_MS = 500                             # longest silence inside a frame
BAUD = 115_200                           # the UART core's default (BAUD_DIV = 0)
# The SoC's hardware watchdog (SYS.WDOG_*), armed by the boot ROM before any
# image runs and unchangeable until reset.  It must outlast the servo
# firmware's longest gap between two feeds: a control period (PERIOD_US at
# most 25 ms) plus one more when the period changes (the next tick moves to
# one new period after the change), with margin; it is also how long a hung
# firmware can keep driving.
WDOG_MS = 100

# ROM layout: bootloader code, then the factory descriptor and image; the key
# slot takes the last auth.KEY_SLOT_BYTES of the ROM.
BOOT_CODE_BYTES = 0x1400                 # 5 KiB: HMAC-SHA-256 and the watchdog
FACTORY_MAGIC = 0x57464C54               # 'TLFW' little-endian
FACTORY_DESC_FMT = "<IIII"               # magic, length, CRC-32, load address
FACTORY_OFS = BOOT_CODE_BYTES
FACTORY_IMAGE_OFS = FACTORY_OFS + struct.calcsize(FACTORY_DESC_FMT)
KEY_SLOT_OFS = regs.BOOT_ROM_SIZE - auth.KEY_SLOT_BYTES
FACTORY_MAX_BYTES = min(KEY_SLOT_OFS - FACTORY_IMAGE_OFS, MAX_IMAGE_BYTES)

# Firmware image header: every image built with firmware/common/crt0.S starts
# with a jump over two words - this magic and the register-map version it was
# built for (firmware/common/link.ld gets both from here).  A raw image is
# uploaded only if it carries them (``torqueloop upload --raw``).
IMAGE_MAGIC = 0x4D494C54                 # 'TLIM' little-endian
IMAGE_MAGIC_OFS = 4
IMAGE_MAP_VERSION = regs.REGMAP_VERSION
IMAGE_HEADER_END = IMAGE_MAGIC_OFS + 8
# ELF: RV32 (class 32, little-endian, EM_RISCV), an executable, no compressed
# instructions (the CPU is RV32IM) and the soft-float ABI.
EM_RISCV = 243
ET_EXEC = 2
EF_RISCV_RVC = 0x1
EF_RISCV_FLOAT_ABI = 0x6

REPLY_PREFIX = b"TLB"
REPLY_BYTES = len(REPLY_PREFIX) + 2      # prefix, code, newline


def ms_to_cycles(ms: int, clk_hz: int = regs.CLK_HZ) -> int:
    return clk_hz // 1000 * ms


class Reply(enum.Enum):
    """The bootloader's one-letter reply codes (sent as ``TLB<code>\\n``)."""
    WINDOW = "W"        # window open, send now
    OK = "K"            # image accepted, starting it
    BAD_HEADER = "H"    # header CRC, version or load address wrong
    BAD_LENGTH = "L"    # length 0 or larger than MAX_IMAGE_BYTES
    TIMEOUT = "T"       # frame interrupted (gap longer than GAP_MS)
    BAD_CRC = "C"       # image CRC-32 mismatch
    GARBAGE = "G"       # bytes in the window but no sync
    AUTH = "A"          # image MAC does not verify under the board's key
    NO_KEY = "X"        # the board has no key: every upload is refused
    FACTORY = "F"       # factory firmware copied to RAM and starting
    NO_FACTORY = "N"    # no valid factory image in ROM: listening without timeout

    @property
    def is_error(self) -> bool:
        return self in ERRORS


ERRORS = frozenset({Reply.BAD_HEADER, Reply.BAD_LENGTH, Reply.TIMEOUT, Reply.BAD_CRC, Reply.GARBAGE, Reply.AUTH,
                    Reply.NO_KEY})
REPLY_TEXT = {
    Reply.WINDOW: "bootloader listening",
    Reply.OK: "image accepted and started",
    Reply.BAD_HEADER: "header rejected (header CRC, version or load address)",
    Reply.BAD_LENGTH: f"length 0 or larger than {MAX_IMAGE_BYTES} bytes",
    Reply.TIMEOUT: f"frame interrupted (no byte for {GAP_MS} ms)",
    Reply.BAD_CRC: "image CRC-32 mismatch",
    Reply.GARBAGE: "bytes but no sync in the window",
    Reply.AUTH: "authentication failed: the image's MAC does not verify under the board's key "
                "(signed with another key, or not at all)",
    Reply.NO_KEY: "the board has no key provisioned, so it refuses every upload (docs/security.md)",
    Reply.FACTORY: "factory firmware started",
    Reply.NO_FACTORY: "no factory firmware in ROM, waiting for an upload",
}


def crc32(data: bytes) -> int:
    """CRC-32/ISO-HDLC (zlib, Ethernet): reflected 0xEDB88320, init/xorout all ones."""
    return zlib.crc32(data) & 0xFFFFFFFF


# --- frames ---------------------------------------------------------------------

class FrameError(ValueError):
    pass


def encode_header(length: int, image_crc: int, load_addr: int = LOAD_ADDR, version: int = VERSION) -> bytes:
    """Sync + header + header CRC, without any range check (benches build bad ones on purpose)."""
    hdr = struct.pack(HEADER_FMT, version, 0, 0, load_addr, length, image_crc)
    return SYNC + hdr + struct.pack("<I", crc32(hdr))


def encode_frame(image: bytes, key: bytes) -> bytes:
    """The upload frame for a flat RAM image, signed with ``key`` (docs/bootloader.md, 'Upload frame')."""
    if not image:
        raise FrameError("empty image")
    if len(image) > MAX_IMAGE_BYTES:
        raise FrameError(f"image is {len(image)} bytes, the bootloader takes at most {MAX_IMAGE_BYTES}")
    head = encode_header(len(image), crc32(image))
    return head + image + auth.upload_tag(key, head[len(SYNC):len(SYNC) + HEADER_BYTES], image)


def frame_bytes(image_bytes: int) -> int:
    """Bytes on the wire for an image of this size: header, image, MAC."""
    return FRAME_OVERHEAD + image_bytes + TAG_BYTES


def frame_tag_ok(frame: bytes, key: bytes) -> bool:
    """Does the MAC after the image verify under ``key`` (the bootloader's last check)?"""
    _, _, length, _ = decode_header(frame)
    image = frame[FRAME_OVERHEAD:FRAME_OVERHEAD + length]
    tag = frame[FRAME_OVERHEAD + length:FRAME_OVERHEAD + length + TAG_BYTES]
    return auth.upload_tag(key, frame[len(SYNC):len(SYNC) + HEADER_BYTES], image) == tag


def decode_header(frame: bytes) -> tuple[int, int, int, int]:
    """(version, load address, length, image CRC) of a frame; raises FrameError if it is bad."""
    if len(frame) < FRAME_OVERHEAD or frame[:len(SYNC)] != SYNC:
        raise FrameError("no sync")
    hdr = frame[len(SYNC):len(SYNC) + HEADER_BYTES]
    (hcrc,) = struct.unpack_from("<I", frame, len(SYNC) + HEADER_BYTES)
    if crc32(hdr) != hcrc:
        raise FrameError("header CRC mismatch")
    version, z0, z1, load, length, icrc = struct.unpack(HEADER_FMT, hdr)
    if version != VERSION or z0 or z1 or load != LOAD_ADDR:
        raise FrameError("bad version or load address")
    return version, load, length, icrc


class ReplyParser:
    """Picks ``TLB<code>\\n`` replies out of a byte stream that may also carry
    RN-XV text and servo link frames."""

    def __init__(self) -> None:
        self._buf = bytearray()

    def feed(self, data: bytes) -> list[Reply]:
        self._buf += data
        out: list[Reply] = []
        while True:
            i = self._buf.find(REPLY_PREFIX)
            if i < 0:
                del self._buf[:max(0, len(self._buf) - (len(REPLY_PREFIX) - 1))]
                return out
            if len(self._buf) < i + REPLY_BYTES:
                del self._buf[:i]
                return out
            code, nl = chr(self._buf[i + 3]), self._buf[i + 4]
            try:
                if nl != 0x0A:
                    raise ValueError
                out.append(Reply(code))
                del self._buf[:i + REPLY_BYTES]
            except ValueError:
                del self._buf[:i + 1]


# --- images ---------------------------------------------------------------------

class ImageError(ValueError):
    pass


def image_from_elf(raw: bytes) -> bytes:
    """Flat RAM image of a RAM-linked RV32 ELF: its PT_LOAD file bytes from
    the load address, gaps zero-filled (.bss has no file bytes and is left to
    the image's crt0).  Refuses anything that is not a firmware image for this
    board: not RV32 (class, byte order, machine, compressed or float ABI), not
    an executable, a segment outside program RAM, or not starting and entering
    at the RAM base (the bootloader jumps there)."""
    if len(raw) < 52 or raw[:4] != b"\x7fELF":
        raise ImageError("not an ELF file")
    if raw[4] != 1 or raw[5] != 1:
        raise ImageError("not a 32-bit little-endian ELF (the board runs RV32)")
    (etype, machine, _v, entry, phoff, _sh, flags, _eh, phentsize, phnum) = struct.unpack_from("<HHIIIIIHHH", raw, 16)
    if machine != EM_RISCV:
        raise ImageError(f"ELF machine {machine} is not RISC-V")
    if etype != ET_EXEC:
        raise ImageError(f"ELF type {etype} is not an executable (link it with firmware/common/link.ld)")
    if flags & EF_RISCV_RVC:
        raise ImageError("ELF uses compressed instructions (RVC); the board's CPU is RV32IM: build with -march=rv32im")
    if flags & EF_RISCV_FLOAT_ABI:
        raise ImageError("ELF uses a hardware-float ABI; the board's CPU has no FPU: build with -mabi=ilp32")
    if phentsize < 32 or phoff + phnum * phentsize > len(raw):
        raise ImageError("truncated ELF: program headers run past the end of the file")
    segs = []
    ram_end = regs.RAM_BASE + regs.RAM_SIZE
    for i in range(phnum):
        p_type, off, _va, paddr, filesz, memsz, _f, _a = struct.unpack_from("<8I", raw, phoff + i * phentsize)
        if p_type != 1 or not memsz:
            continue
        if not (regs.RAM_BASE <= paddr and paddr + max(memsz, filesz) <= ram_end):
            raise ImageError(f"segment at 0x{paddr:08x}..0x{paddr + max(memsz, filesz):08x} lies outside program "
                             f"RAM 0x{regs.RAM_BASE:08x}..0x{ram_end:08x}")
        if filesz:
            if off + filesz > len(raw):
                raise ImageError("truncated ELF")
            segs.append((paddr, raw[off:off + filesz]))
    if not segs:
        raise ImageError("ELF has no loadable bytes")
    segs.sort()
    if segs[0][0] != LOAD_ADDR or entry != LOAD_ADDR:
        raise ImageError(f"image loads at 0x{segs[0][0]:08x} and enters at 0x{entry:08x}; the bootloader "
                         f"loads and enters at 0x{LOAD_ADDR:08x} (link with firmware/common/link.ld)")
    out = bytearray()
    for addr, data in segs:
        pos = addr - LOAD_ADDR
        if pos < len(out):
            raise ImageError(f"overlapping segments at 0x{addr:08x}")
        out += bytes(pos - len(out)) + data
    return bytes(out)


def check_header(img: bytes) -> None:
    """A raw image must carry the firmware image header (firmware/common/crt0.S)."""
    if len(img) < IMAGE_HEADER_END:
        raise ImageError(f"{len(img)} bytes: too short for a firmware image")
    magic, version = struct.unpack_from("<II", img, IMAGE_MAGIC_OFS)
    if magic != IMAGE_MAGIC:
        raise ImageError(f"no firmware image header (magic 0x{IMAGE_MAGIC:08x} at byte {IMAGE_MAGIC_OFS}, "
                         f"found 0x{magic:08x}): not a torqueloop firmware image")
    if version != IMAGE_MAP_VERSION:
        raise ImageError(f"image built for register map version {version}, this board's is {IMAGE_MAP_VERSION}")


def load_image(path: str | Path, raw_ok: bool = False) -> bytes:
    """The RAM image to upload: an ELF (checked and converted), or with
    ``raw_ok`` a flat binary that carries the firmware image header.  Raises
    ImageError with one line saying why anything else is refused."""
    data = Path(path).read_bytes()
    if data[:4] == b"\x7fELF":
        img = image_from_elf(data)
    elif raw_ok:
        check_header(data)
        img = data
    else:
        raise ImageError("not an ELF file; a raw binary is uploaded only with --raw (and must carry the "
                         "firmware image header)")
    if not img:
        raise ImageError("empty image")
    if len(img) > MAX_IMAGE_BYTES:
        raise ImageError(f"{len(img)} bytes, the bootloader takes at most {MAX_IMAGE_BYTES}")
    return img


# --- boot ROM contents ------------------------------------------------------------

def rom_image(boot_code: bytes, factory: bytes | None, key: bytes | None = None,
              rom_bytes: int = regs.BOOT_ROM_SIZE) -> bytes:
    """Boot ROM bytes: bootloader code at 0, the factory descriptor at
    FACTORY_OFS and the factory image after it (docs/bootloader.md, 'ROM layout'),
    the key slot at the end (docs/security.md).  Without a factory image the
    descriptor is zero (the bootloader then says N); without a key the slot is
    zero (the board refuses uploads and motion commands)."""
    if len(boot_code) > BOOT_CODE_BYTES:
        raise ImageError(f"bootloader is {len(boot_code)} bytes, its ROM slot {BOOT_CODE_BYTES}")
    rom = bytearray(boot_code) + bytes(BOOT_CODE_BYTES - len(boot_code))
    if factory is not None:
        if not factory or len(factory) > FACTORY_MAX_BYTES:
            raise ImageError(f"factory image is {len(factory)} bytes, the ROM has room for {FACTORY_MAX_BYTES}")
        rom += struct.pack(FACTORY_DESC_FMT, FACTORY_MAGIC, len(factory), crc32(factory), LOAD_ADDR) + factory
    return bytes(rom) + bytes(rom_bytes - auth.KEY_SLOT_BYTES - len(rom)) + auth.key_slot(key)


def hex_words(data: bytes) -> str:
    """$readmemh text: one little-endian 32-bit word per line, word 0 first."""
    data += bytes(-len(data) % 4)
    return "".join(f"{int.from_bytes(data[i:i + 4], 'little'):08x}\n" for i in range(0, len(data), 4))


