# SPDX-License-Identifier: MIT
"""bootloader: the boot ROM bootloader (firmware/boot) on the whole SoC.

The boot ROM holds the real bootloader (built with a short window and gap and
the UART at 1 Mbaud, so the bench is fast) and a stand-in factory firmware
(prog/factory.c, which shows on the LEDs whether it started from a pristine
copy).  Frames come from torqueloop.spec.bootproto, the code the host tool uses;
an independent UART model (cocotbext-uart) drives RX and reads TX.

Checked: no upload -> factory after the window; a good upload runs (LEDs,
UART), hands back to the bootloader by the documented jump and loads again;
bad image CRC, bad header, oversized length, truncated frame, bytes without a
sync, an image signed with another key are each answered with their error
reply and the factory firmware runs pristine (a half-written or unsigned
image never runs); a ROM without a key refuses a correctly signed upload;
RN-XV chatter in front of a frame does no harm; the window closes when
configured.  The board's real window (500 ms = 25 000 000 cycles) is read
from the board build's ELF.  The ROM holds auth.TEST_KEY (docs/security.md).
"""

from __future__ import annotations

import os
import random
from pathlib import Path

import cocotb
import pytest
from cocotb.triggers import ClockCycles, FallingEdge, Timer, with_timeout

from torqueloop.spec import auth
from torqueloop.spec import bootproto as bp
from torqueloop.flow.simrun import run
from torqueloop.flow import boot_image as build_boot
from torqueloop.flow.tb_images import BOOT_TB_BAUD_DIV, BOOT_TB_CFG, TB_KEY, boot_tb_prog

import tbutil

CLK_NS = 20
BAUD_DIV = BOOT_TB_BAUD_DIV        # 50 clocks per bit: 1 Mbaud
BAUD = 50_000_000 // (BAUD_DIV + 1)
BYTE_CYCLES = 10 * (BAUD_DIV + 1)
TB_CFG = BOOT_TB_CFG
FACTORY_LEDS, DIRTY_LEDS, APP_LEDS = 0x0F0, 0x3FF, 0x2A5
KEY = TB_KEY


def signed(image: bytes, key: bytes = KEY) -> bytes:
    return bp.encode_frame(image, key)


build_prog = boot_tb_prog


class TB:
    def __init__(self, dut, quiet: bool = False) -> None:
        self.dut = dut
        tbutil.idle_soc_pins(dut)
        self.src, self.sink = tbutil.uart_models(dut.uart_rx, dut.uart_tx, BAUD, quiet=quiet)
        tbutil.start_clock(dut, CLK_NS)

    @property
    def cycle(self) -> int:
        return tbutil.cycle_now(CLK_NS)

    async def reset(self) -> int:
        """Reset the SoC (RAM keeps its contents, as on the board); returns
        the cycle at which the first start bit of the bootloader's TLBW appears."""
        self.dut.rst.value = 1
        await ClockCycles(self.dut.clk, 10)
        self.sink.clear()
        self.dut.rst.value = 0
        # the bootloader readies the key (~55 000 cycles) before it says TLBW
        await with_timeout(FallingEdge(self.dut.uart_tx), 100_000 * CLK_NS, "ns")
        t_tx = self.cycle
        assert await self.line() == b"TLBW\n"
        return t_tx

    async def line(self, limit_cycles: int = 400_000) -> bytes:
        got = bytearray()
        while not got.endswith(b"\n"):
            got += await with_timeout(self.sink.read(1), limit_cycles * 20, "ns")
        return bytes(got)

    async def expect(self, *lines: bytes, limit_cycles: int = 400_000) -> None:
        for want in lines:
            got = await self.line(limit_cycles)
            assert got == want, f"expected {want!r}, got {got!r}"

    async def leds_settle(self, want: int) -> None:
        await ClockCycles(self.dut.clk, 200)
        assert int(self.dut.ledr.value) == want, f"LEDR 0x{int(self.dut.ledr.value):03x}, want 0x{want:03x}"

    async def factory_runs(self) -> None:
        await self.expect(b"TLBF\n", b"FAC\n")
        await self.leds_settle(FACTORY_LEDS)


def _images() -> tuple[bytes, bytes]:
    return (bytes.fromhex(os.environ["TB_APP_HEX"]), bytes.fromhex(os.environ["TB_FACTORY_HEX"]))


def _app_variant(app: bytes) -> bytes:
    """The app plus random trailing bytes (covered by the CRC, cleared as .bss
    or never read), so each upload's content and length differ."""
    return app + bytes(random.getrandbits(8) for _ in range(random.randrange(0, 64)))


@cocotb.test()
async def no_upload_runs_factory(dut):
    tb = TB(dut)
    await tb.reset()
    await tb.factory_runs()
    # A second reset with the factory's own dirty RAM: copied fresh again.
    await tb.reset()
    await tb.factory_runs()


@cocotb.test()
async def good_upload_runs_and_hands_back(dut):
    tb = TB(dut)
    app, _ = _images()
    await tb.reset()
    await tb.src.write(b"*OPEN*" + signed(_app_variant(app)))   # RN-XV chatter first: harmless
    await tb.expect(b"TLBK\n", b"APP\n")
    await tb.leds_settle(APP_LEDS)
    # The app jumps to the boot ROM (the entry convention); a second upload loads.
    await tb.src.write(b"B")
    await tb.expect(b"TLBW\n")
    await tb.src.write(signed(_app_variant(app)))
    await tb.expect(b"TLBK\n", b"APP\n")
    # After a reset without an upload the factory firmware runs, pristine.
    await tb.reset()
    await tb.factory_runs()


async def _rejected(dut, data: bytes, code: bytes) -> None:
    tb = TB(dut)
    await tb.reset()
    await tb.src.write(data)
    await tb.expect(b"TLB" + code + b"\n")
    await tb.factory_runs()


@cocotb.test()
async def bad_crc_rejected(dut):
    app, _ = _images()
    frame = bytearray(signed(_app_variant(app)))
    bit = random.randrange(bp.FRAME_OVERHEAD * 8, (len(frame) - bp.TAG_BYTES) * 8)
    frame[bit // 8] ^= 1 << (bit % 8)
    await _rejected(dut, bytes(frame), b"C")


@cocotb.test()
async def bad_header_rejected(dut):
    app, _ = _images()
    frame = bytearray(signed(app))
    bit = random.randrange(len(bp.SYNC) * 8, bp.FRAME_OVERHEAD * 8)
    frame[bit // 8] ^= 1 << (bit % 8)
    await _rejected(dut, bytes(frame), b"H")


@cocotb.test()
async def oversized_rejected(dut):
    app, _ = _images()
    # A well-formed header (its CRC is right) announcing one byte too many.
    hdr = bp.encode_header(bp.MAX_IMAGE_BYTES + 1, bp.crc32(app))
    await _rejected(dut, hdr + app, b"L")


@cocotb.test()
async def truncated_rejected_and_half_image_never_runs(dut):
    app, _ = _images()
    frame = signed(_app_variant(app))
    cut = random.randrange(bp.FRAME_OVERHEAD + 16, len(frame) - 1)   # part of the app (or all) is already in RAM
    await _rejected(dut, frame[:cut], b"T")


@cocotb.test()
async def image_signed_with_another_key_never_runs(dut):
    """The CRC is right, the MAC is not this board's: A, then the factory
    firmware, pristine, although the whole image sat in RAM."""
    app, _ = _images()
    await _rejected(dut, signed(_app_variant(app), key=bytes(range(32))), b"A")


@cocotb.test()
async def garbage_without_sync_rejected(dut):
    junk = b"*HELLO*" + bytes(random.choice(b"ABCDEFGHIJKLMNOPQRSTUVWXYZ*\r\n") for _ in range(20))
    await _rejected(dut, junk, b"G")


@cocotb.test()
async def window_closes_when_configured(dut):
    """The sync's first byte lands in the RX FIFO ~9.5 bit times after its
    start bit; the window is counted from just before TLBW is sent."""
    tb = TB(dut)
    app, _ = _images()
    margin = 2_000
    for offset, accepted in ((-margin, True), (+margin, False)):
        t0 = await tb.reset()
        await Timer((t0 + TB_CFG.window_cycles + offset - BYTE_CYCLES - tb.cycle) * CLK_NS, unit="ns")
        await tb.src.write(signed(app))
        if accepted:
            await tb.expect(b"TLBK\n", b"APP\n")
        else:
            await tb.factory_runs()
            await tb.src.wait()
            await ClockCycles(dut.clk, 4 * BYTE_CYCLES)
            late = tb.sink.read_nowait(tb.sink.count()) if tb.sink.count() else b""
            assert b"TLB" not in late, f"bootloader answered after its window: {late!r}"


@cocotb.test(skip="TB_SERVO" not in os.environ)
async def servo_factory_answers_and_hands_over(dut):
    """With the real servo firmware as the factory image (bench_bootloader
    runs this; it costs a 17 KiB copy and CRC in simulation): it boots after
    the window, answers IDENTIFY, and its BOOTLOADER command brings back the
    bootloader, which then loads an upload."""
    from torqueloop.spec import protocol as P

    tb = TB(dut)
    app, _ = _images()
    t0 = await tb.reset()
    await tb.expect(b"TLBF\n", limit_cycles=4_000_000)
    t_f = tb.cycle
    # Let the servo firmware reach its main loop first: it clears INTC.PENDING
    # after start-up, and a byte already waiting in the RX FIFO then never
    # raises the UART_RX edge again (reported to the firmware owner).
    await Timer(2_000, unit="us")
    dec = P.FrameDecoder()

    async def transact(name: str, seq: int, wire: bytes | None = None, **fields) -> dict:
        await tb.src.write(wire or P.request(name, seq, **fields))
        for _ in range(2000):
            for f in dec.feed(await with_timeout(tb.sink.read(1), 4_000_000 * CLK_NS, "ns")):
                if isinstance(f, P.Frame) and f.cmd == P.COMMANDS[name].cmd | 0x80:
                    return P.decode_reply(f)
        raise AssertionError(f"no {name} reply")

    ident = await transact("IDENTIFY", 1)
    assert ident["status"] == 0 and ident["clk_hz"] == 50_000_000, ident
    t_id = tb.cycle
    rep = await transact("BOOTLOADER", ident["last_seq"] + 1, magic=P.BOOTLOADER_MAGIC)
    assert rep["status"] == P.STATUS["AUTH"], f"BOOTLOADER without the key: {rep}"
    hn = auth.new_host_nonce()
    sess = auth.open_session(KEY, hn, await transact("SESSION", 0, host_nonce=hn))
    seq = ident["last_seq"] + 1
    rep = await transact("BOOTLOADER", seq, sess.request("BOOTLOADER", seq, magic=P.BOOTLOADER_MAGIC))
    assert rep["status"] == 0, rep
    await tb.expect(b"TLBW\n")
    await tb.src.write(signed(app))
    await tb.expect(b"TLBK\n", b"APP\n")
    cocotb.log.info(f"servo factory: TLBF {t_f - t0} cycles after TLBW, IDENTIFY answered at {t_id - t0}")
    Path(os.environ["TB_SERVO"]).write_text(f"{t_f - t0} {t_id - t0}\n")


@cocotb.test(skip="TB_NO_FACTORY" not in os.environ)
async def no_factory_waits_for_an_upload(dut):
    """A ROM without a factory image (bench_bootloader runs this): N, then
    the window stays open without a timeout until an upload arrives."""
    tb = TB(dut)
    app, _ = _images()
    await tb.reset()
    await tb.expect(b"TLBN\n", b"TLBW\n")
    await Timer(3 * TB_CFG.window_cycles * CLK_NS, unit="ns")
    assert tb.sink.count() == 0, "the second window must not time out"
    await tb.src.write(b"*OPEN*" + signed(_app_variant(app)))
    await tb.expect(b"TLBK\n", b"APP\n")
    await tb.leds_settle(APP_LEDS)


@cocotb.test(skip="TB_NO_KEY" not in os.environ)
async def no_key_refuses_every_upload(dut):
    """A ROM built without a key (test_bootloader runs this on the same
    model with the ROM file rewritten): a correctly signed image is refused
    with X before any of it reaches RAM, and the factory firmware runs."""
    app, _ = _images()
    await _rejected(dut, signed(_app_variant(app)), b"X")


@cocotb.test(skip="TB_MEASURE" not in os.environ)
async def measure_upload_mac(dut):
    """Benchmark (scripts/benches/bench_auth.py): the bootloader checks the
    MAC after the last byte, over the image in RAM.  Cycles from the frame's
    last stop bit to the end of TLBK for two image sizes: their difference
    per KiB is the MAC's cost of an uploaded kilobyte (the CRC-32 runs while
    the bytes arrive)."""
    tb = TB(dut, quiet=True)
    app, _ = _images()
    out = {}
    for kib in (1, 9):
        image = app + bytes(kib * 1024 - len(app))
        await tb.reset()
        await tb.src.write(signed(image))
        await tb.src.wait()
        t0 = tb.cycle
        await tb.expect(b"TLBK\n", limit_cycles=4_000_000)
        out[kib] = tb.cycle - t0
        await tb.expect(b"APP\n")
    per_kib = (out[9] - out[1]) / 8
    cocotb.log.info(f"upload MAC: {out} cycles after the last byte; {per_kib:.0f} cycles per KiB")
    Path(os.environ["TB_MEASURE"]).write_text(f"{out[1]} {out[9]} {per_kib}\n")


def test_board_window_is_500ms():
    """The board build (defaults) keeps 500 ms at 50 MHz in its ROM image."""
    b = build_boot.build_boot()
    assert build_boot.symbol_word(b.elf, "boot_window_cycles") == 25_000_000 == bp.ms_to_cycles(500)
    assert build_boot.symbol_word(b.elf, "boot_gap_cycles") == bp.ms_to_cycles(bp.GAP_MS)
    assert b.code_bytes <= bp.BOOT_CODE_BYTES


@pytest.mark.parametrize("sim", ["verilator"])
def test_bootloader(sim):
    app, factory = build_prog("app"), build_prog("factory")
    rom = build_boot.build_rom(factory, TB_CFG, name="tb_rom", key=KEY)
    env = {"TB_APP_HEX": app.hex(), "TB_FACTORY_HEX": factory.hex()}
    run("soc", sim, "test_bootloader", parameters={"ROM_INIT": f'"{rom}"'}, build_tag="bootloader", extra_env=env)
    # the same model, its ROM file rewritten without the key
    build_boot.build_rom(factory, TB_CFG, name="tb_rom", key=None)
    try:
        run("soc", sim, "test_bootloader", parameters={"ROM_INIT": f'"{rom}"'}, build_tag="bootloader",
            testcase="no_key_refuses_every_upload", extra_env=env | {"TB_NO_KEY": "1"})
    finally:
        build_boot.build_rom(factory, TB_CFG, name="tb_rom", key=KEY)
