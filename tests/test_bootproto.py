# SPDX-License-Identifier: MIT
"""torqueloop.spec.bootproto: frame layout and its MAC, CRC-32 (host and the
bootloader's C code), reply parsing, ROM layout with the key slot, ELF
conversion, and upload() over a TCP socket to a fake bootloader (the RN-XV
path: socket://host:port)."""

from __future__ import annotations

import hashlib
import hmac
import random
import socket
import struct
import subprocess
import threading
import time
import zlib
from pathlib import Path

import pytest

from torqueloop.host import upload
from torqueloop.spec import auth
from torqueloop.spec import bootproto as bp
from torqueloop.spec import regs

KEY = auth.TEST_KEY

REPO = Path(__file__).resolve().parent.parent


def test_crc32_check_value():
    assert bp.crc32(b"123456789") == 0xCBF43926


def test_boot_crc_c_matches_zlib(tmp_path):
    """firmware/boot/boot_crc.c compiled for the host against zlib on random data."""
    drv = tmp_path / "drv.c"
    drv.write_text('#include <stdio.h>\n#include "boot_crc.h"\n'
                   "int main(void){uint32_t s=BOOT_CRC_INIT;int c;while((c=getchar())!=EOF)"
                   "s=boot_crc_byte(s,(uint8_t)c);printf(\"%08x\\n\",~s);return 0;}\n")
    exe = tmp_path / "drv"
    subprocess.run(["gcc", "-std=c11", "-Wall", "-Werror", "-I", str(REPO / "firmware" / "boot"), "-o", str(exe),
                    str(drv), str(REPO / "firmware" / "boot" / "boot_crc.c")], check=True)
    seed = random.randrange(2**32)
    print(f"seed {seed}")
    rng = random.Random(seed)
    for n in (0, 1, 9, 1000, 4093):
        data = bytes(rng.getrandbits(8) for _ in range(n))
        out = subprocess.run([str(exe)], input=data, capture_output=True, check=True).stdout
        assert int(out, 16) == zlib.crc32(data), f"length {n}"


def test_frame_layout():
    image = bytes(range(256)) * 3 + b"\x01"
    f = bp.encode_frame(image, KEY)
    assert f[:4] == bytes([0xA5, 0x5A, 0xB0, 0x07])
    version, z0, z1, z2, load, length, icrc, hcrc = struct.unpack_from("<BBBBIIII", f, 4)
    assert (version, z0, z1, z2) == (2, 0, 0, 0)
    assert load == regs.RAM_BASE == 0x8000_0000
    assert length == len(image) and icrc == zlib.crc32(image)
    assert hcrc == zlib.crc32(f[4:20])
    assert f[24:24 + len(image)] == image and bp.FRAME_OVERHEAD == 24
    assert len(f) == bp.frame_bytes(len(image)) == 24 + len(image) + 32
    # the MAC, computed here with hmac directly: HMAC-SHA-256(key, "TLUP" | header without sync | image)
    assert f[-32:] == hmac.new(KEY, b"TLUP" + f[4:20] + image, hashlib.sha256).digest()
    assert bp.decode_header(f)[1:] == (regs.RAM_BASE, len(image), zlib.crc32(image))


def test_frame_mac_covers_header_and_image():
    rng = random.Random(77)
    image = rng.randbytes(300)
    f = bp.encode_frame(image, KEY)
    assert bp.frame_tag_ok(f, KEY) and not bp.frame_tag_ok(f, bytes(32))
    for bit in rng.sample(range(4 * 8, len(f) * 8), 200):
        if 20 * 8 <= bit < 24 * 8:
            continue                      # the header's own CRC: not under the MAC, checked by the CRC
        g = bytearray(f)
        g[bit // 8] ^= 1 << (bit % 8)
        try:
            assert not bp.frame_tag_ok(bytes(g), KEY), f"bit {bit} flipped, MAC still good"
        except bp.FrameError:
            pass                          # a header flip is already caught by the header CRC


def test_frame_limits_and_bad_headers():
    assert bp.MAX_IMAGE_BYTES == regs.RAM_SIZE - bp.BOOT_STACK_BYTES
    bp.encode_frame(bytes(bp.MAX_IMAGE_BYTES), KEY)
    with pytest.raises(bp.FrameError):
        bp.encode_frame(bytes(bp.MAX_IMAGE_BYTES + 1), KEY)
    with pytest.raises(bp.FrameError):
        bp.encode_frame(b"", KEY)
    f = bytearray(bp.encode_frame(b"abcd", KEY))
    for bit in range(32, 24 * 8):   # every single-bit flip of the header or its CRC is caught
        g = bytearray(f)
        g[bit // 8] ^= 1 << (bit % 8)
        with pytest.raises(bp.FrameError):
            bp.decode_header(bytes(g))
    with pytest.raises(bp.FrameError):
        bp.decode_header(bp.encode_header(4, 0, load_addr=0x1000) + b"abcd")


def test_sync_is_not_rn_xv_text_or_cobs_delimiter():
    assert bp.SYNC[0] >= 0x80 and 0 not in bp.SYNC   # RN-XV text is ASCII: it cannot even start a sync
    for text in (b"*HELLO*", b"*OPEN*", b"*CLOS*", b"CMD\r\n"):
        assert bp.SYNC not in text


def test_reply_parser_with_chatter_and_splits():
    stream = b"*OPEN*TLBW\n\x00\x05xyTLBZ\nTLBC\nTL" + b"BF\nTLB"
    p = bp.ReplyParser()
    got = []
    for i in range(0, len(stream), 3):
        got += p.feed(stream[i:i + 3])
    assert got == [bp.Reply.WINDOW, bp.Reply.BAD_CRC, bp.Reply.FACTORY]
    assert p.feed(b"K\n") == [bp.Reply.OK]


def test_rom_image_layout():
    boot = bytes(range(200))
    factory = random.Random(1001).randbytes(1001)   # fixed data: no seed to report
    rom = bp.rom_image(boot, factory, KEY)
    code = bp.BOOT_CODE_BYTES
    assert len(rom) == regs.BOOT_ROM_SIZE and code == 0x1400
    assert rom[:200] == boot and rom[200:code] == bytes(code - 200)
    magic, length, crc, load = struct.unpack_from("<IIII", rom, code)
    assert (magic, length, crc, load) == (0x57464C54, 1001, zlib.crc32(factory), regs.RAM_BASE)
    assert rom[code + 16:code + 16 + 1001] == factory
    assert rom[code + 16 + 1001:-64] == bytes(regs.BOOT_ROM_SIZE - 64 - code - 16 - 1001)
    # the key slot: the last 64 bytes, 'TLKY', algorithm 1, the key, HMAC(key, "TLKC")[:4]
    assert rom[-64:-56] == b"TLKY" + struct.pack("<I", 1) and rom[-56:-24] == KEY
    assert rom[-24:-20] == hmac.new(KEY, b"TLKC", hashlib.sha256).digest()[:4] and rom[-20:] == bytes(20)
    assert auth.parse_key_slot(rom[bp.KEY_SLOT_OFS:]) == KEY
    assert bp.rom_image(boot, factory)[-64:] == bytes(64), "no key: a blank slot"
    assert bp.rom_image(boot, None)[code:code + 16] == bytes(16)
    with pytest.raises(bp.ImageError):
        bp.rom_image(bytes(bp.BOOT_CODE_BYTES + 1), factory)
    with pytest.raises(bp.ImageError):
        bp.rom_image(boot, bytes(bp.FACTORY_MAX_BYTES + 1))
    assert len(bp.rom_image(boot, bytes(bp.FACTORY_MAX_BYTES), KEY)) == regs.BOOT_ROM_SIZE
    words = bp.hex_words(b"\x01\x02\x03\x04\x05").split()
    assert words == ["04030201", "00000005"]


def _elf(segments: list[tuple[int, bytes]], entry: int, *, cls: int = 1, order: int = 1, etype: int = 2,
         machine: int = 243, flags: int = 0, bss: int = 16) -> bytes:
    """A minimal ELF32 RISC-V file with PT_LOAD segments (written here
    independently of bootproto's reader)."""
    phoff, phent = 52, 32
    data_off = phoff + phent * len(segments)
    hdr = b"\x7fELF" + bytes([cls, order, 1]) + bytes(9)
    hdr += struct.pack("<HHIIIIIHHHHHH", etype, machine, 1, entry, phoff, 0, flags, 52, phent, len(segments), 40, 0, 0)
    ph, body = b"", b""
    for addr, d in segments:
        ph += struct.pack("<8I", 1, data_off + len(body), addr, addr, len(d), len(d) + bss, 7, 4)
        body += d
    return hdr + ph + body


def test_image_from_elf(tmp_path):
    base = regs.RAM_BASE
    raw = _elf([(base + 0x10, b"BBBB"), (base, b"AAAA")], base)
    assert bp.image_from_elf(raw) == b"AAAA" + bytes(12) + b"BBBB"
    with pytest.raises(bp.ImageError):
        bp.image_from_elf(_elf([(0, b"AAAA")], 0))           # linked for the ROM
    with pytest.raises(bp.ImageError):
        bp.image_from_elf(_elf([(base, b"AAAA")], base + 4))  # entry elsewhere
    for cut in (10, 40, 60, len(raw) - 2):                  # truncated anywhere: ImageError, never struct.error
        with pytest.raises(bp.ImageError):
            bp.image_from_elf(raw[:cut])



def test_only_firmware_for_this_board_is_uploaded(tmp_path):
    """`torqueloop upload` took a 12-byte text file and 3 kB of random
    bytes as raw images.  Now: an RV32 ELF inside program RAM, or a raw binary
    with --raw and the firmware image header; anything else is refused."""
    base, end = regs.RAM_BASE, regs.RAM_BASE + regs.RAM_SIZE
    good = [(base, b"AAAA")]
    refused = {
        "64-bit ELF": _elf(good, base, cls=2),
        "big-endian ELF": _elf(good, base, order=2),
        "x86 ELF": _elf(good, base, machine=62),
        "shared object": _elf(good, base, etype=3),
        "compressed instructions": _elf(good, base, flags=1),
        "hard-float ABI": _elf(good, base, flags=4),
        "segment past the end of RAM": _elf([(base, b"AAAA"), (end - 4, b"BBBBBBBB")], base),
        "bss past the end of RAM": _elf([(base, b"AAAA"), (end - 8, b"BB")], base, bss=16),
        "segment in the ROM": _elf([(0, b"AAAA"), (base, b"BBBB")], base),
    }
    for why, raw in refused.items():
        with pytest.raises(bp.ImageError):
            bp.image_from_elf(raw)
            pytest.fail(why)
    assert bp.image_from_elf(_elf(good, base)) == b"AAAA"
    header = b"\x6f\x00\xc0\x00" + struct.pack("<II", bp.IMAGE_MAGIC, bp.IMAGE_MAP_VERSION)
    files = {"text.txt": b"hello world\n", "random.bin": bytes(random.Random(3).randrange(256) for _ in range(3000)),
             "image.bin": header + bytes(100), "old_map.bin": header[:8] + struct.pack("<I", 99) + bytes(100)}
    for name, data in files.items():
        (tmp_path / name).write_bytes(data)
    for name in files:                              # without --raw nothing but an ELF
        with pytest.raises(bp.ImageError, match="--raw"):
            bp.load_image(tmp_path / name)
    for name in ("text.txt", "random.bin", "old_map.bin"):
        with pytest.raises(bp.ImageError):
            bp.load_image(tmp_path / name, raw_ok=True)
    assert bp.load_image(tmp_path / "image.bin", raw_ok=True) == files["image.bin"]


def test_c_header_carries_the_protocol():
    from torqueloop.flow.boot_image import boot_proto_header

    h = boot_proto_header()
    assert "#define BOOT_WINDOW_CYCLES 25000000u" in h
    assert "#define BOOT_SYNC_BYTES {0xA5u, 0x5Au, 0xB0u, 0x07u}" in h
    assert f"#define BOOT_MAX_IMAGE_BYTES {bp.MAX_IMAGE_BYTES}u" in h
    assert "#define BOOT_REPLY_BAD_CRC 'C'" in h
    assert "#define BOOT_REPLY_AUTH 'A'" in h and "#define BOOT_REPLY_NO_KEY 'X'" in h
    assert f"#define BOOT_TAG_BYTES 32u" in h and '#define BOOT_LABEL_UPLOAD "TLUP"' in h


class FakeBoot(threading.Thread):
    """A TCP peer that acts like the bootloader behind an RN-XV: says TLBW,
    reads one frame with its own parser and answers K, or C + F if asked to
    find the CRC bad, or A + F if the MAC after the image is not the test key's
    (computed here with hmac directly)."""

    def __init__(self, corrupt: bool = False, silent: bool = False, wait_enter: bool = True) -> None:
        super().__init__(daemon=True)
        self.srv = socket.create_server(("127.0.0.1", 0))
        self.port = self.srv.getsockname()[1]
        self.corrupt, self.silent, self.wait_enter = corrupt, silent, wait_enter
        self.received = b""
        self.entered = b""

    def run(self) -> None:
        conn, _ = self.srv.accept()
        with conn:
            # Like the servo firmware: nothing until the host's enter command
            # (pyserial drops what arrives while it opens the socket).
            if self.wait_enter:
                buf = conn.recv(4096)
            else:           # a board reset by hand: the window opens on its own
                time.sleep(0.3)
                buf = b""
            if self.silent:
                time.sleep(1.0)
                return
            conn.sendall(b"*HELLO*TLBW\n")
            while bp.SYNC not in buf or len(buf) < buf.index(bp.SYNC) + 24 + 32 + struct.unpack_from(
                    "<I", buf, buf.index(bp.SYNC) + 12)[0]:
                chunk = conn.recv(4096)
                if not chunk:
                    return
                buf += chunk
            self.entered = buf[:buf.index(bp.SYNC)]
            buf = buf[buf.index(bp.SYNC):]
            self.received = buf
            length, crc = struct.unpack_from("<II", buf, 12)
            mac = hmac.new(KEY, b"TLUP" + buf[4:20] + buf[24:24 + length], hashlib.sha256).digest()
            if zlib.crc32(buf[24:24 + length]) != crc or self.corrupt:
                conn.sendall(b"TLBC\nTLBF\n")
            elif buf[24 + length:24 + length + 32] != mac:
                conn.sendall(b"TLBA\nTLBF\n")
            else:
                conn.sendall(b"TLBK\n")


def test_upload_over_tcp_good_and_rejected():
    image = random.Random(3000).randbytes(3000)
    fake = FakeBoot()
    fake.start()
    seen = []
    res = upload.upload(f"socket://127.0.0.1:{fake.port}", image, key=KEY, baud=2_000_000, wait_window_s=5,
                        enter=b"ENTER", progress=lambda n, t: seen.append((n, t)))
    fake.join(5)
    assert res.ok, res.message
    assert fake.entered == b"ENTER"
    assert fake.received == bp.encode_frame(image, KEY)
    assert res.bytes_sent == bp.frame_bytes(len(image))
    assert seen[-1] == (res.bytes_sent, res.bytes_sent) and [n for n, _ in seen] == sorted(n for n, _ in seen)
    assert res.replies == [bp.Reply.WINDOW, bp.Reply.OK]

    bad = FakeBoot(corrupt=True)
    bad.start()
    res = upload.upload(f"socket://127.0.0.1:{bad.port}", image, key=KEY, baud=2_000_000, wait_window_s=5,
                        enter=b"E")
    bad.join(5)
    assert not res.ok and "CRC" in res.message and res.factory_running

    other = FakeBoot()
    other.start()
    res = upload.upload(f"socket://127.0.0.1:{other.port}", image, key=bytes(32), baud=2_000_000, wait_window_s=5,
                        enter=b"E")
    other.join(5)
    assert not res.ok and res.message.startswith("rejected: authentication failed") and res.factory_running


def test_upload_without_window_sends_nothing():
    fake = FakeBoot(silent=True)
    fake.start()
    res = upload.upload(f"socket://127.0.0.1:{fake.port}", b"abcd", key=KEY, wait_window_s=0.3, enter=b"E")
    assert not res.ok and "TLBW" in res.message and res.bytes_sent == 0


def test_upload_reports_a_lost_link():
    fake = FakeBoot(silent=True)
    fake.start()
    res = upload.upload(f"socket://127.0.0.1:{fake.port}", b"abcd", key=KEY, wait_window_s=3, enter=b"E")
    assert not res.ok and "link" in res.message




def test_upload_script_over_tcp(tmp_path, capsys, monkeypatch):
    image = tmp_path / "app.bin"
    header = b"\x6f\x00\xc0\x00" + struct.pack("<II", bp.IMAGE_MAGIC, bp.IMAGE_MAP_VERSION)
    image.write_bytes(header + random.Random(500).randbytes(500 - len(header)))
    keyfile = tmp_path / "link.key"
    auth.write_key_file(keyfile, KEY)
    monkeypatch.delenv(auth.KEY_FILE_ENV, raising=False)
    args = [str(image), "--port", "socket://127.0.0.1:9", "--baud", "1000000", "--wait", "5"]
    assert upload.main(args) == 2, "a raw image needs --raw"
    args.append("--raw")
    capsys.readouterr()
    assert upload.main(args) == 1 and "--key-file" in capsys.readouterr().err      # no key: nothing opened
    fake = FakeBoot(wait_enter=False)
    fake.start()
    args[2] = f"socket://127.0.0.1:{fake.port}"
    monkeypatch.setenv(auth.KEY_FILE_ENV, str(keyfile))
    rc = upload.main(args)
    out = capsys.readouterr()
    assert rc == 0, out
    assert fake.received == bp.encode_frame(image.read_bytes(), KEY)
    assert out.out.splitlines()[-1].startswith("OK: 500 bytes") and "556/556 bytes" in out.err


def test_upload_script_enter_asks_the_servo_firmware():
    """--enter: IDENTIFY, SESSION, then BOOTLOADER with the magic, the next
    seq and its MAC in the session, checked with the servo protocol's own
    decoder and hmac directly."""
    from torqueloop.spec import protocol as P

    ident, sess = P.COMMANDS["IDENTIFY"], P.COMMANDS["SESSION"]
    payload = struct.pack(ident.rep_fmt, *[{"status": 0, "last_seq": 41}.get(n, 1) for n, _ in ident.rep])
    board_nonce = bytes(range(16))

    class Port:
        def __init__(self) -> None:
            self.rx, self.tx = b"", b""
            self.dec = P.FrameDecoder()

        in_waiting = property(lambda self: len(self.rx))

        def write(self, b: bytes) -> None:
            self.tx += b
            for f in self.dec.feed(b):
                if f.cmd == ident.cmd:
                    self.rx += P.encode_frame(0, ident.cmd | 0x80, payload)
                elif f.cmd == sess.cmd:
                    proof = hmac.new(KEY, b"TLSP" + f.payload + board_nonce, hashlib.sha256).digest()[:16]
                    self.rx += P.encode_frame(f.seq, sess.cmd | 0x80, b"\x00" + board_nonce + proof)

        def read(self, n: int) -> bytes:
            out, self.rx = self.rx[:n], self.rx[n:]
            return out

    port = Port()
    enter = upload.servo_enter(port, KEY)
    frames = [f for f in P.FrameDecoder().feed(enter) if isinstance(f, P.Frame)]
    assert len(frames) == 1 and frames[0].cmd == P.COMMANDS["BOOTLOADER"].cmd and frames[0].seq == 42
    magic, tag = frames[0].payload[:4], frames[0].payload[4:]
    assert struct.unpack("<I", magic) == (P.BOOTLOADER_MAGIC,)
    host_nonce = [f for f in P.FrameDecoder().feed(port.tx) if f.cmd == sess.cmd][0].payload
    want = hmac.new(KEY, b"TLCF" + board_nonce + host_nonce + struct.pack("<HBB", 42, 0x0A, 20) + magic,
                    hashlib.sha256).digest()[:16]
    assert tag == want
    sent = [f for f in P.FrameDecoder().feed(port.tx) if isinstance(f, P.Frame)]
    assert [f.cmd for f in sent] == [ident.cmd, sess.cmd]
    with pytest.raises(auth.AuthError, match="authentication failed"):
        upload.servo_enter(Port(), bytes(32))            # a board holding another key


def test_key_provisioning_puts_the_key_file_into_the_boot_rom(tmp_path, capsys, monkeypatch):
    """docs/security.md, 'Key provisioning': the ROM image the FPGA loads holds
    the named key file's key in its key slot; without one the slot is blank
    and the build says what that board will refuse."""
    from torqueloop.flow import boot_image

    key = auth.new_key()
    kf = tmp_path / "board.key"
    auth.write_key_file(kf, key)
    monkeypatch.delenv(auth.KEY_FILE_ENV, raising=False)

    def slot(out: Path) -> bytes:
        words = (out / "boot_rom.hex").read_text().split()
        return b"".join(int(w, 16).to_bytes(4, "little") for w in words)[bp.KEY_SLOT_OFS:]

    assert boot_image.main(["--no-factory", "--out", str(tmp_path / "a"), "--key-file", str(kf)]) == 0
    assert auth.parse_key_slot(slot(tmp_path / "a")) == key
    assert f"key id {auth.key_id(key)}" in capsys.readouterr().out
    assert boot_image.main(["--no-factory", "--out", str(tmp_path / "c")]) == 0
    assert slot(tmp_path / "c") == bytes(auth.KEY_SLOT_BYTES)
    assert "refuses motion" in capsys.readouterr().err
    kf.chmod(0o644)
    with pytest.raises(SystemExit, match="chmod 600"):       # refused before anything is built
        boot_image.main(["--no-factory", "--out", str(tmp_path / "d"), "--key-file", str(kf)])
