# SPDX-License-Identifier: MIT
"""What authentication costs (docs/security.md): HMAC-SHA-256, which the
protocol uses, against SipHash-2-4, the measured alternative.

1. The primitives on the CPU's RTL (scripts/run_elf.py, cpu_sim_top,
   mcycle around the firmware's own C; firmware/tests/crypto_bench.c built
   -O2 as the servo firmware and -Os as the bootloader): the check of one
   authenticated frame, a SESSION, the key's setup, and both MACs over the
   frame's message and per KiB.  The MACs the RTL computed are compared with
   Python's hmac and torqueloop.spec.auth.siphash24.
2. In the running servo firmware on the SoC (tb/firmware
   measure_authentication): a STOP with and without its MAC, a SESSION, and
   the worst control iteration and interrupt lateness meanwhile.
3. In the bootloader on the SoC (tb/bootloader measure_upload_mac): cycles
   per uploaded KiB of the MAC check after the last byte.
4. Code: the authentication's share of the servo image and the bootloader's slot.
"""

from __future__ import annotations

import hashlib
import hmac
import json
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from torqueloop.flow import boot_image, firmware, tb_images
from torqueloop.flow.simrun import run
from torqueloop.spec import auth, bootproto, regs
from torqueloop.spec.repo import REPO_ROOT as REPO

FW = REPO / "firmware"
PROGS = REPO / "tb" / "cpu" / "progs"
NAMES = ["sha_block", "verify", "session", "hmac_1k", "hmac_4k", "sip_frame", "sip_1k", "sip_4k", "key_setup",
         "verify_status"]
MHZ = regs.CLK_HZ / 1e6


def _build(opt: str, out: Path) -> Path:
    elf = out / f"crypto_bench{opt}.elf"
    cmd = [firmware.CC, "-march=rv32im_zicsr", "-mabi=ilp32", opt, "-nostdlib", "-ffreestanding", "-static",
           "-std=c11", "-Wall", "-Wextra", "-Werror", f"-I{PROGS}", f"-I{FW / 'include'}", f"-I{FW / 'crypto'}",
           f"-I{FW / 'protocol'}", "-T", str(PROGS / "link.ld"), "-Wl,--no-warn-rwx-segments", "-o", str(elf),
           str(PROGS / "crt0.S"), str(FW / "tests" / "crypto_bench.c"), str(FW / "crypto" / "tl_siphash.c"),
           *map(str, firmware.AUTH_SOURCES), str(FW / "protocol" / "tl_link.c"), str(FW / "common" / "mem.c"),
           firmware.libgcc()]
    subprocess.run(cmd, check=True, capture_output=True, text=True)
    return elf


def primitives(opt: str) -> dict:
    with tempfile.TemporaryDirectory() as d:
        elf = _build(opt, Path(d))
        sig = Path(d) / "sig"
        r = subprocess.run([sys.executable, str(REPO / "scripts" / "run_elf.py"), str(elf), "--signature", str(sig)],
                           capture_output=True, text=True)
        if r.returncode:
            raise RuntimeError(r.stdout + r.stderr)
        words = [int(w, 16) for w in sig.read_text().split()]
    m = dict(zip(NAMES, words))
    # the RTL computed what the host computes
    buf = bytes((i * 7 + 3) & 0xFF for i in range(4096))
    key = bytes(range(32))
    got = b"".join(w.to_bytes(4, "little") for w in words[len(NAMES):len(NAMES) + 8])
    assert got == hmac.new(key, buf[:1024], hashlib.sha256).digest(), "HMAC-SHA-256 on the RTL differs from hmac"
    sip = words[len(NAMES) + 8] | words[len(NAMES) + 9] << 32
    assert sip == auth.siphash24(key[:16], buf[:1024]), "SipHash-2-4 on the RTL differs from the Python oracle"
    assert m["verify_status"] == 0
    m["hmac_per_kib"] = (m["hmac_4k"] - m["hmac_1k"]) / 3
    m["sip_per_kib"] = (m["sip_4k"] - m["sip_1k"]) / 3
    return m


def in_firmware() -> dict:
    img = tb_images.servo_tb_image()
    out = REPO / "build" / "firmware" / "auth_measure.json"
    run("soc", "verilator", "test_firmware", bench="firmware",
        parameters={"RAM_INIT": f'"{img.ram_hex}"', "ROM_INIT": f'"{img.rom_hex}"'},
        testcase="measure_authentication",
        extra_env={"TL_AUTH_MEASURE": "1", "TL_AUTH_MEASURE_OUT": str(out)})
    return json.loads(out.read_text())


def in_bootloader() -> tuple[int, int, float]:
    app, factory = tb_images.boot_tb_prog("app"), tb_images.boot_tb_prog("factory")
    rom = boot_image.build_rom(factory, tb_images.BOOT_TB_CFG, name="tb_rom", key=tb_images.TB_KEY)
    with tempfile.TemporaryDirectory() as d:
        out = Path(d) / "times"
        run("soc", "verilator", "test_bootloader", parameters={"ROM_INIT": f'"{rom}"'}, build_tag="bootloader", bench="bootloader",
            testcase="measure_upload_mac",
            extra_env={"TB_APP_HEX": app.hex(), "TB_FACTORY_HEX": factory.hex(), "TB_MEASURE": str(out)})
        a, b, per = out.read_text().split()
    return int(a), int(b), float(per)


def code_sizes() -> tuple[int, int, int]:
    img = firmware.build("servo")
    nm = subprocess.run(["riscv64-unknown-elf-nm", "-S", str(img.elf)], capture_output=True, text=True,
                        check=True).stdout
    crypto = sum(int(f[1], 16) for f in (ln.split() for ln in nm.splitlines())
                 if len(f) == 4 and (f[3].startswith(("tl_sha256", "tl_hmac", "tl_auth", "tl_keyslot", "tl_ct_"))
                                     or f[3] in ("compress", "K", "H0")))
    return img.text_bytes, crypto, boot_image.build_boot().code_bytes


def us(c: float) -> str:
    return f"{c / MHZ:,.0f} us" if c / MHZ < 10_000 else f"{c / MHZ / 1000:,.1f} ms"


def main() -> int:
    t0 = time.monotonic()
    o2, os_ = primitives("-O2"), primitives("-Os")
    print("primitives on the CPU RTL (cpu_sim_top, mcycle; MACs checked against hmac and the SipHash oracle):")
    print(f"  {'':38s} {'-O2 (firmware)':>16s} {'-Os (bootloader)':>18s}")
    rows = [("SHA-256 of 55 B (one compression)", "sha_block"),
            ("check of one authenticated frame", "verify"), ("SESSION (nonce + proof)", "session"),
            ("key setup (HMAC ipad/opad states)", "key_setup"),
            ("SipHash-2-4 of the frame's message", "sip_frame"),
            ("HMAC-SHA-256 per KiB", "hmac_per_kib"), ("SipHash-2-4 per KiB", "sip_per_kib")]
    for label, k in rows:
        print(f"  {label:38s} {o2[k]:>9,.0f} cycles {os_[k]:>11,.0f} cycles   ({us(o2[k])} at {MHZ:g} MHz)")
    print(f"  HMAC-SHA-256 / SipHash-2-4: {o2['verify'] / o2['sip_frame']:.1f}x per frame, "
          f"{o2['hmac_per_kib'] / o2['sip_per_kib']:.1f}x per KiB")
    f = in_firmware()
    print(f"servo firmware on the SoC (Verilator, {f['period_us']} us period, 1 Mbaud; fastest of 12): "
          f"STOP {f['stop_cycles']:,.0f} cycles, with its MAC {f['stop_authenticated_cycles']:,.0f}: "
          f"{f['frame_auth_cycles']:,.0f} cycles = {us(f['frame_auth_cycles'])} per authenticated frame; "
          f"SESSION {f['session_cycles']:,.0f} cycles")
    print(f"  meanwhile: worst control iteration {f['loop_cycles_max']} cycles, worst interrupt lateness "
          f"{f['jitter_cycles_max']} cycles (authentication runs in the main loop, never in the interrupt)")
    a, b, per = in_bootloader()
    print(f"bootloader on the SoC: MAC check after the last byte {a:,} cycles (1 KiB image), {b:,} (9 KiB): "
          f"{per:,.0f} cycles = {us(per)} per KiB")
    text, crypto, boot = code_sizes()
    servo_kib = text / 1024
    print(f"  the servo image ({servo_kib:.1f} KiB) costs {us(per * servo_kib)} after its last byte; the largest "
          f"upload ({bootproto.MAX_IMAGE_BYTES // 1024} KiB) {us(per * bootproto.MAX_IMAGE_BYTES / 1024)} "
          f"(on the wire at 115200 baud: {bootproto.frame_bytes(text) * 10 / bootproto.BAUD:.1f} s and "
          f"{bootproto.frame_bytes(bootproto.MAX_IMAGE_BYTES) * 10 / bootproto.BAUD:.1f} s)")
    print(f"code: authentication {crypto} B of the servo image's {text} B (factory slot "
          f"{bootproto.FACTORY_MAX_BYTES} B); bootloader {boot} of {bootproto.BOOT_CODE_BYTES} B")
    print(f"({time.monotonic() - t0:.0f} s)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
