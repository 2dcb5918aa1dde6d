# SPDX-License-Identifier: MIT
"""The firmware's own cryptography (firmware/crypto, firmware/protocol/tl_auth.c)
on the host with ASan + UBSan, against three oracles: the published test
vectors (RFC 4231 for HMAC-SHA-256, FIPS 180-2's examples for SHA-256, the
SipHash reference implementation's 64 vectors), Python's hashlib/hmac on
random inputs (``TL_SEED=`` reruns), and torqueloop/spec/auth.py - the
host's half of the protocol - for the session's nonce, proof and frame tags."""

from __future__ import annotations

import hashlib
import hmac
import os
import random
import struct
import subprocess
from pathlib import Path

import pytest

from torqueloop.spec import auth as A
from torqueloop.spec import protocol as P
from torqueloop.spec.repo import REPO_ROOT

FW = REPO_ROOT / "firmware"
OUT = REPO_ROOT / "build" / "firmware" / "host"
SOURCES = [FW / "tests" / "crypto_cli.c", FW / "crypto" / "tl_sha256.c", FW / "crypto" / "tl_siphash.c",
           FW / "protocol" / "tl_keyslot.c", FW / "protocol" / "tl_auth.c", FW / "protocol" / "tl_link.c"]
SAN = ["-fsanitize=address,undefined", "-fno-sanitize-recover=all"]

# RFC 4231 section 4: (key, data, HMAC-SHA-256); case 5's result is truncated to 128 bits.
RFC4231 = [
    (b"\x0b" * 20, b"Hi There", "b0344c61d8db38535ca8afceaf0bf12b881dc200c9833da726e9376c2e32cff7"),
    (b"Jefe", b"what do ya want for nothing?", "5bdcc146bf60754e6a042426089575c75a003f089d2739839dec58b964ec3843"),
    (b"\xaa" * 20, b"\xdd" * 50, "773ea91e36800e46854db8ebd09181a72959098b3ef8c122d9635514ced565fe"),
    (bytes(range(1, 26)), b"\xcd" * 50, "82558a389a443c0ea4cc819899f2083a85f0faa3e578f8077a2e3ff46729665b"),
    (b"\x0c" * 20, b"Test With Truncation", "a3b6167473100ee06e0c796c2955552b"),
    (b"\xaa" * 131, b"Test Using Larger Than Block-Size Key - Hash Key First",
     "60e431591ee0b67f0d8a26aacbf5b77f8e0bc6213728c5140546040f0ee37f54"),
    (b"\xaa" * 131, b"This is a test using a larger than block-size key and a larger than block-size data. "
                    b"The key needs to be hashed before being used by the HMAC algorithm.",
     "9b09ffa71b942fcb27635fbcd5b0e944bfdc63644f0713938a7f51535c3a35e2"),
]
# FIPS 180-2 appendix B: one block, two blocks.
SHA256_VECTORS = [
    (b"abc", "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad"),
    (b"abcdbcdecdefdefgefghfghighijhijkijkljklmklmnlmnomnopnopq",
     "248d6a61d20638b8e5c026930c3e6039a33ce45964ff2167f6ecedd419db06c1"),
    (b"", "e3b0c44298fc1c149afbf4c8996fb92427ae41e4649b934ca495991b7852b855"),
]
# SipHash-2-4 reference implementation (Aumasson and Bernstein), vectors.h: key 00 01 .. 0f,
# message 00 01 .. (n - 1) for n = 0 .. 63; each the tag's 8 bytes in order.
SIPHASH_VECTORS = """
310e0edd47db6f72 fd67dc93c539f874 5a4fa9d909806c0d 2d7efbd796666785 b7877127e09427cf 8da699cd64557618
cee3fe586e46c9cb 37d1018bf50002ab 6224939a79f5f593 b0e4a90bdf82009e f3b9dd94c5bb5d7a a7ad6b22462fb3f4
fbe50e86bc8f1e75 903d84c02756ea14 eef27a8e90ca23f7 e545be4961ca29a1 db9bc2577fcc2a3f 9447be2cf5e99a69
9cd38d96f0b3c14b bd6179a71dc96dbb 98eea21af25cd6be c7673b2eb0cbf2d0 883ea3e395675393 c8ce5ccd8c030ca8
94af49f6c650adb8 eab8858ade92e1bc f315bb5bb835d817 adcf6b0763612e2f a5c91da7acaa4dde 716595876650a2a6
28ef495c53a387ad 42c341d8fa92d832 ce7cf2722f512771 e37859f94623f3a7 381205bb1ab0e012 ae97a10fd434e015
b4a31508beff4d31 81396229f0907902 4d0cf49ee5d4dcca 5c73336a76d8bf9a d0a704536ba93e0e 925958fcd6420cad
a915c29bc8067318 952b79f3bc0aa6d4 f21df2e41d4535f9 87577519048f53a9 10a56cf5dfcd9adb eb75095ccd986cd0
51a9cb9ecba312e6 96afadfc2ce666c7 72fe52975a4364ee 5a1645b276d592a1 b274cb8ebf87870a 6f9bb4203de7b381
eaecb2a30b22a87f 9924a43cc1315724 bd838d3aafbf8db7 0b1a2a3265d51aea 135079a3231ce660 932b2846e4d70666
e1915f5cb1eca46c f325965ca16d629f 575ff28e60381be5 724506eb4c328a95
""".split()


def _h(b: bytes) -> str:
    return b.hex() or "-"


class Cli:
    def __init__(self, exe: Path) -> None:
        self.p = subprocess.Popen([str(exe)], stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True)

    def __call__(self, *words: str) -> str:
        assert self.p.stdin and self.p.stdout
        self.p.stdin.write(" ".join(words) + "\n")
        self.p.stdin.flush()
        out = self.p.stdout.readline()
        assert out, f"crypto_cli died on {words[0]}"
        return out.strip()

    def close(self) -> None:
        assert self.p.stdin
        self.p.stdin.close()
        assert self.p.wait(30) == 0, "crypto_cli failed (sanitizer report?)"


@pytest.fixture(scope="module")
def cli():
    OUT.mkdir(parents=True, exist_ok=True)
    exe = OUT / "crypto_cli"
    tmp = OUT / f"crypto_cli.{os.getpid()}"
    subprocess.run(["gcc", "-std=c11", "-O1", "-g", "-Wall", "-Wextra", "-Werror", *SAN,
                    f"-I{FW / 'crypto'}", f"-I{FW / 'protocol'}", *map(str, SOURCES), "-o", str(tmp)], check=True)
    os.replace(tmp, exe)
    c = Cli(exe)
    yield c
    c.close()


def _seed() -> int:
    seed = int(os.environ.get("TL_SEED", random.randrange(1, 2**32)))
    print(f"seed {seed} (TL_SEED={seed} reruns)")
    return seed


def test_rfc4231(cli) -> None:
    for i, (key, data, want) in enumerate(RFC4231, 1):
        py = hmac.new(key, data, hashlib.sha256).hexdigest()
        assert py.startswith(want), f"RFC 4231 case {i}: Python's hmac disagrees with the RFC"
        assert cli("H", _h(key), _h(data)).startswith(want), f"RFC 4231 case {i}"
        assert cli("I", _h(key), _h(data)).startswith(want), f"RFC 4231 case {i}, byte by byte"


def test_sha256_vectors_and_every_padding_length(cli) -> None:
    for msg, want in SHA256_VECTORS:
        assert cli("S", _h(msg)) == want
    # 0..200 bytes: every position of the 0x80 byte and the length, across one and two final blocks
    for n in range(201):
        msg = bytes((7 * i + n) & 0xFF for i in range(n))
        assert cli("S", _h(msg)) == hashlib.sha256(msg).hexdigest(), f"{n} bytes"


def test_hmac_against_python_on_random_inputs(cli) -> None:
    rng = random.Random(_seed())
    for _ in range(400):
        key = rng.randbytes(rng.choice([0, 1, 16, 32, 63, 64, 65, rng.randrange(200)]))
        msg = rng.randbytes(rng.choice([0, 55, 56, 63, 64, 65, 119, 120, rng.randrange(3000)]))
        want = hmac.new(key, msg, hashlib.sha256).hexdigest()
        assert cli("H", _h(key), _h(msg)) == want, f"key {key.hex()} msg {len(msg)} bytes"
    key, msg = rng.randbytes(32), rng.randbytes(1000)
    assert cli("I", _h(key), _h(msg)) == hmac.new(key, msg, hashlib.sha256).hexdigest()


def test_siphash_reference_vectors(cli) -> None:
    key = bytes(range(16))
    assert len(SIPHASH_VECTORS) == 64
    for n, want in enumerate(SIPHASH_VECTORS):
        msg = bytes(range(n))
        assert A.siphash24(key, msg).to_bytes(8, "little").hex() == want, f"Python, {n} bytes"
        assert cli("P", _h(key), _h(msg)) == want, f"C, {n} bytes"
    # the SipHash paper's worked example (appendix A): 15 bytes -> a129ca6149be45e5
    assert A.siphash24(key, bytes(range(15))) == 0xA129CA6149BE45E5


def test_siphash_c_against_python_on_random_inputs(cli) -> None:
    rng = random.Random(_seed())
    for _ in range(300):
        key, msg = rng.randbytes(16), rng.randbytes(rng.randrange(2000))
        assert cli("P", _h(key), _h(msg)) == A.siphash24(key, msg).to_bytes(8, "little").hex()


def test_key_slot(cli) -> None:
    """The firmware takes a key from exactly the slots auth.key_slot writes;
    any flipped bit of magic, algorithm, key or check makes it a board without a key."""
    rng = random.Random(_seed())
    key = rng.randbytes(A.KEY_BYTES)
    slot = A.key_slot(key)
    assert A.parse_key_slot(slot) == key and cli("K", slot.hex()) == "1"
    assert A.parse_key_slot(A.key_slot(None)) is None and cli("K", A.key_slot(None).hex()) == "0"
    for bit in rng.sample(range((8 + A.KEY_BYTES + A.KEY_CHECK_BYTES) * 8), 40):
        bad = bytearray(slot)
        bad[bit // 8] ^= 1 << (bit % 8)
        assert A.parse_key_slot(bytes(bad)) is None
        assert cli("K", bad.hex()) == "0", f"bit {bit} flipped: the firmware still found a key"


def test_session_nonce_proof_and_frame_tags_agree_with_the_host(cli) -> None:
    """Both halves of the protocol from their own code: the board's nonce,
    proof and its check of frames (C) against auth.py (Python)."""
    rng = random.Random(_seed())
    key = rng.randbytes(A.KEY_BYTES)
    assert cli("K", A.key_slot(key).hex()) == "1"
    pool = bytes(32)
    for count in range(3):
        hn, cycles, stir = rng.randbytes(16), rng.randrange(2**32), rng.randrange(2**32)
        st, bn, proof, new_pool = cli("N", hn.hex(), str(cycles), str(stir)).split()
        want = A.board_nonce(key, pool, count, cycles, stir, hn)
        assert int(st) == P.STATUS["OK"] and new_pool == want.hex() and bn == want[:A.NONCE_BYTES].hex()
        pool = want
        sess = A.open_session(key, hn, {"board_nonce": bytes.fromhex(bn), "proof": bytes.fromhex(proof)})
        with pytest.raises(A.AuthError, match="authentication failed"):
            A.open_session(rng.randbytes(A.KEY_BYTES), hn, {"board_nonce": bytes.fromhex(bn),
                                                           "proof": bytes.fromhex(proof)})
        seq = rng.randrange(2**16)
        payload = rng.randbytes(6)
        tag = sess.tag(seq, 5, payload)
        for bit in range(8 * A.TAG_BYTES):          # every bit of a tag matters
            bad = bytearray(tag)
            bad[bit // 8] ^= 1 << (bit % 8)
            assert cli("V", str(seq), "5", _h(payload + bad)) == str(P.STATUS["AUTH"]), f"tag bit {bit}"
        for k in range(20):
            payload = rng.randbytes(rng.randrange(P.MAX_PAYLOAD - A.TAG_BYTES + 1))
            cmd, s = rng.randrange(256), (seq + k) & 0xFFFF
            tag = sess.tag(s, cmd, payload)
            assert cli("T", str(s), str(cmd), _h(payload)) == tag.hex()
            assert cli("V", str(s), str(cmd), _h(payload + tag)) == str(P.STATUS["OK"])
            assert cli("V", str(s), str(cmd), _h(payload + tag)) == str(P.STATUS["REPLAY"]), "accepted twice"
            bad = bytearray(payload + tag)
            i = rng.randrange(len(bad))
            bad[i] ^= 1 << rng.randrange(8)
            assert cli("V", str((s + 1) & 0xFFFF), str(cmd), _h(bytes(bad))) == str(P.STATUS["AUTH"])
            assert cli("V", str((s + 1) & 0xFFFF), str(cmd ^ 1), _h(payload + tag)) == str(P.STATUS["AUTH"])


def test_session_seq_window(cli) -> None:
    """Offsets from the session's first authenticated seq only grow, and end at the window."""
    key = bytes(range(A.KEY_BYTES))
    cli("K", A.key_slot(key).hex())
    hn = bytes(16)
    _, bn, proof, _ = cli("N", hn.hex(), "1", "2").split()
    sess = A.Session(key, hn, bytes.fromhex(bn))

    def verify(seq: int) -> int:
        p = b"\x01"
        return int(cli("V", str(seq & 0xFFFF), "6", _h(p + sess.tag(seq & 0xFFFF, 6, p))))

    base = 0xFFF0
    assert verify(base) == P.STATUS["OK"]
    assert verify(base + 5) == P.STATUS["OK"]
    assert verify(base + 3) == P.STATUS["REPLAY"]          # older than the newest
    assert verify(base - 1) == P.STATUS["NO_SESSION"]      # before the session began
    assert verify(base + A.SESSION_WINDOW - 1) == P.STATUS["OK"]
    assert verify(base + A.SESSION_WINDOW) == P.STATUS["NO_SESSION"]   # used up: open a new one
    assert verify(base + 6) == P.STATUS["REPLAY"]
    # a new session starts afresh and old tags fail in it
    cli("N", hn.hex(), "1", "2")
    p = b"\x01"
    assert int(cli("V", str(base + 7), "6", _h(p + sess.tag(base + 7, 6, p)))) == P.STATUS["AUTH"]
