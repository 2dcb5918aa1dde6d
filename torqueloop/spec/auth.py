# SPDX-License-Identifier: MIT
"""Who may change the machine: the link's authenticated sessions and the
MAC of uploaded firmware (docs/security.md), Python side.

The scheme's constants come from the ``[auth]`` table of
``torqueloop/spec/protocol.toml`` (the C side gets them through the
generated ``tl_protocol.h`` and ``boot_proto.h``); this module computes
what the host tool, the simulated boards and the benches need:

- frame tags, session proofs, board nonces and upload tags with the
  standard library's HMAC-SHA-256 (the firmware's own C implementation,
  firmware/crypto/tl_sha256.c, is checked against it and against RFC 4231);
- the boot ROM's key slot (where a board keeps its key);
- key files: how the host tool keeps the key (text, 64 hex digits, readable
  by its owner only), and where it finds one (an option or
  ``$TORQUELOOP_KEY_FILE``, never the command line itself);
- SipHash-2-4, the measured alternative the protocol does not use
  (scripts/benches/bench_auth.py), as the oracle of firmware/crypto/tl_siphash.c.
"""

from __future__ import annotations

import hashlib
import hmac
import os
import re
import stat
import struct
from dataclasses import dataclass
from pathlib import Path

from torqueloop.spec import protocol as P

_A: dict = P.SPEC["auth"]
KEY_BYTES: int = _A["key_bytes"]
TAG_BYTES: int = _A["tag_bytes"]
UPLOAD_TAG_BYTES: int = _A["upload_tag_bytes"]
NONCE_BYTES: int = _A["nonce_bytes"]
SESSION_WINDOW: int = _A["session_window"]
LABEL_FRAME: bytes = _A["label_frame"].encode()
LABEL_PROOF: bytes = _A["label_proof"].encode()
LABEL_NONCE: bytes = _A["label_nonce"].encode()
LABEL_UPLOAD: bytes = _A["label_upload"].encode()
LABEL_CHECK: bytes = _A["label_check"].encode()
KEY_SLOT_BYTES: int = _A["key_slot_bytes"]
KEY_SLOT_MAGIC: int = _A["key_slot_magic"]
KEY_SLOT_ALGORITHM: int = _A["key_slot_algorithm"]
KEY_SLOT_HEAD = "<II"                       # magic, algorithm; then the key and its 4-byte check
KEY_CHECK_BYTES = 4
LABELS = (LABEL_FRAME, LABEL_PROOF, LABEL_NONCE, LABEL_UPLOAD, LABEL_CHECK)

KEY_FILE_ENV = "TORQUELOOP_KEY_FILE"
#: The key of every simulated board the project's own tests and benches build
#: (the RTL benches, the co-simulated experiment).  Public by construction:
#: never provision a real board with it (docs/security.md).
TEST_KEY = hashlib.sha256(b"torqueloop test key - public, for simulations only, never for a board").digest()


class AuthError(ValueError):
    """A MAC or proof that does not verify; the message is meant for a person."""


def hmac256(key: bytes, *parts: bytes) -> bytes:
    return hmac.new(key, b"".join(parts), hashlib.sha256).digest()


# --- the link ----------------------------------------------------------------------

def frame_tag(key: bytes, board_nonce: bytes, host_nonce: bytes, seq: int, cmd: int, payload: bytes) -> bytes:
    """The tag appended to ``payload``: it covers the session's two nonces and
    the frame's header as it goes on the wire (len counts the tag)."""
    head = struct.pack("<HBB", seq & 0xFFFF, cmd, len(payload) + TAG_BYTES)
    return hmac256(key, LABEL_FRAME, board_nonce, host_nonce, head, payload)[:TAG_BYTES]


def session_proof(key: bytes, host_nonce: bytes, board_nonce: bytes) -> bytes:
    """What the board answers SESSION with to show it holds ``key``."""
    return hmac256(key, LABEL_PROOF, host_nonce, board_nonce)[:TAG_BYTES]


def board_nonce(key: bytes, pool: bytes, count: int, cycles: int, stir: int, host_nonce: bytes) -> bytes:
    """The board's generator (firmware/protocol/tl_auth.c): all 32 bytes; the
    first NONCE_BYTES are the challenge, the whole is the next pool."""
    return hmac256(key, LABEL_NONCE, pool, struct.pack("<III", count & 0xFFFFFFFF, cycles & 0xFFFFFFFF,
                                                       stir & 0xFFFFFFFF), host_nonce)


@dataclass(frozen=True)
class Session:
    """The host's half of an open session: tags frames for this board."""
    key: bytes
    host_nonce: bytes
    board_nonce: bytes

    def tag(self, seq: int, cmd: int, payload: bytes) -> bytes:
        return frame_tag(self.key, self.board_nonce, self.host_nonce, seq, cmd, payload)

    def request(self, name: str, seq: int, **fields: int) -> bytes:
        """``protocol.request`` with the tag appended: the frame of an authenticated command."""
        c = P.COMMANDS[name]
        payload = struct.pack(c.req_fmt, *(fields[n] for n, _ in c.req))
        return P.encode_frame(seq, c.cmd, payload + self.tag(seq, c.cmd, payload))


def new_host_nonce() -> bytes:
    return os.urandom(NONCE_BYTES)


def open_session(key: bytes, host_nonce: bytes, reply: dict) -> Session:
    """The session a SESSION reply (decoded, status OK) opens; AuthError if the
    board's proof does not verify under ``key`` (the board holds another key)."""
    bn, proof = reply["board_nonce"], reply["proof"]
    if not hmac.compare_digest(session_proof(key, host_nonce, bn), proof):
        raise AuthError(f"authentication failed: the board's key is not this key (key id {key_id(key)})")
    return Session(key, host_nonce, bn)


def needs_key(name: str, fields: dict[str, int]) -> bool:
    """Does this command need the key (protocol.toml ``auth``; stopping never does)?"""
    c = P.COMMANDS[name]
    if c.auth == "open":
        return False
    return not any(fields.get(f) == v for f, v in c.open_when.items())


def stopping(name: str, fields: dict[str, int]) -> bool:
    """A command that shows the host in control (feeds_link) yet needs no key
    can only take motion away: STOP and disabling.  The board runs it
    whatever its seq, so frames injected into the link cannot block a stop
    (docs/protocol.md); only a fresh one with a verified MAC feeds the link
    watchdog."""
    return P.COMMANDS[name].feeds_link and not needs_key(name, fields)


# --- firmware uploads -------------------------------------------------------------------

def upload_tag(key: bytes, header: bytes, image: bytes) -> bytes:
    """The MAC after the image in an upload frame (docs/bootloader.md)."""
    return hmac256(key, LABEL_UPLOAD, header, image)[:UPLOAD_TAG_BYTES]


# --- the key slot in the boot ROM -------------------------------------------------------

def key_check(key: bytes) -> bytes:
    return hmac256(key, LABEL_CHECK)[:KEY_CHECK_BYTES]


def key_id(key: bytes) -> str:
    """A name for a key that gives nothing of it away: its check value in hex.
    ``torqueloop key id`` and the boot ROM build print it, so a person can
    tell which key a board was built with."""
    return key_check(key).hex()


def key_slot(key: bytes | None) -> bytes:
    """The KEY_SLOT_BYTES at the top of the boot ROM; all zero without a key."""
    if key is None:
        return bytes(KEY_SLOT_BYTES)
    _check_key(key)
    raw = struct.pack(KEY_SLOT_HEAD, KEY_SLOT_MAGIC, KEY_SLOT_ALGORITHM) + key + key_check(key)
    return raw + bytes(KEY_SLOT_BYTES - len(raw))


def parse_key_slot(raw: bytes) -> bytes | None:
    """The key in a slot, or None if it holds none (or a damaged one: the
    firmware checks the same fields and refuses the same way)."""
    if len(raw) < KEY_SLOT_BYTES:
        return None
    magic, alg = struct.unpack_from(KEY_SLOT_HEAD, raw)
    o = struct.calcsize(KEY_SLOT_HEAD)
    key, check = raw[o:o + KEY_BYTES], raw[o + KEY_BYTES:o + KEY_BYTES + KEY_CHECK_BYTES]
    if magic != KEY_SLOT_MAGIC or alg != KEY_SLOT_ALGORITHM or key_check(key) != check:
        return None
    return key


def _check_key(key: bytes) -> None:
    if not isinstance(key, bytes) or len(key) != KEY_BYTES:
        raise KeyFileError(f"a link key is {KEY_BYTES} bytes")


# --- key files ---------------------------------------------------------------------------

class KeyFileError(ValueError):
    """A key file that is missing, unreadable, malformed or readable by others."""


_HEX = re.compile(r"^[0-9a-fA-F]{%d}$" % (2 * KEY_BYTES))


def new_key() -> bytes:
    return os.urandom(KEY_BYTES)


def format_key_file(key: bytes) -> str:
    _check_key(key)
    return (f"# torqueloop link key (HMAC-SHA-256, docs/security.md), key id {key_id(key)}.\n"
            "# Secret: keep this file off the network and out of version control; give it to the\n"
            "# tool with --key-file or $TORQUELOOP_KEY_FILE, never on the command line.\n"
            f"{key.hex()}\n")


def write_key_file(path: str | Path, key: bytes) -> None:
    """Create ``path`` (mode 0600; an existing file is never overwritten)."""
    path = Path(path)
    try:
        fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o600)
    except FileExistsError:
        raise KeyFileError(f"{path} exists: a key file is never overwritten (remove it first if you mean it)") from None
    except OSError as e:
        raise KeyFileError(f"cannot create {path}: {e.strerror}") from None
    with os.fdopen(fd, "w") as f:
        f.write(format_key_file(key))


def read_key_file(path: str | Path, check_mode: bool = True) -> bytes:
    """The key in ``path``; KeyFileError (one line) for anything else.  On
    POSIX a file other users may read is refused, as ssh refuses a private key."""
    path = Path(path)
    try:
        st = path.stat()
        text = path.read_text(encoding="ascii", errors="replace")
    except FileNotFoundError:
        if _HEX.match(path.name):
            raise KeyFileError("that looks like a key, not a key file: a key given on the command line ends up in "
                               "the shell history and the process list; put it in a file (mode 600) and name "
                               "the file") from None
        raise KeyFileError(f"no key file at {path} (create one with `torqueloop key new {path}`)") from None
    except IsADirectoryError:
        raise KeyFileError(f"{path} is a directory, not a key file") from None
    except OSError as e:
        raise KeyFileError(f"cannot read key file {path}: {e.strerror}") from None
    if check_mode and os.name == "posix" and st.st_mode & (stat.S_IRWXG | stat.S_IRWXO):
        raise KeyFileError(f"key file {path} is accessible by other users (mode {stat.S_IMODE(st.st_mode):04o}): "
                           f"chmod 600 {path}")
    lines = [ln.strip() for ln in text.splitlines() if ln.strip() and not ln.lstrip().startswith("#")]
    if len(lines) != 1 or not _HEX.match(lines[0]):
        raise KeyFileError(f"{path} is not a torqueloop key file (one line of {2 * KEY_BYTES} hex digits; "
                           "`torqueloop key new FILE` writes one)")
    return bytes.fromhex(lines[0])


def key_file_path(option: str | Path | None, environ: dict[str, str] | None = None) -> Path | None:
    """Where the key is: the option if given, else ``$TORQUELOOP_KEY_FILE``, else nowhere."""
    if option:
        return Path(option).expanduser()
    env = (os.environ if environ is None else environ).get(KEY_FILE_ENV, "")
    return Path(env).expanduser() if env else None


# --- SipHash-2-4 (measured, not used by the protocol) --------------------------------------

_M64 = (1 << 64) - 1


def _rotl(x: int, n: int) -> int:
    return ((x << n) | (x >> (64 - n))) & _M64


def siphash24(key: bytes, data: bytes) -> int:
    """SipHash-2-4 (Aumasson and Bernstein 2012) of ``data`` under a 16-byte key."""
    if len(key) != 16:
        raise ValueError("SipHash takes a 16-byte key")
    k0, k1 = struct.unpack("<QQ", key)
    v = [k0 ^ 0x736F6D6570736575, k1 ^ 0x646F72616E646F6D, k0 ^ 0x6C7967656E657261, k1 ^ 0x7465646279746573]

    def rnd() -> None:
        v[0] = (v[0] + v[1]) & _M64; v[1] = _rotl(v[1], 13) ^ v[0]; v[0] = _rotl(v[0], 32)  # noqa: E702
        v[2] = (v[2] + v[3]) & _M64; v[3] = _rotl(v[3], 16) ^ v[2]                          # noqa: E702
        v[0] = (v[0] + v[3]) & _M64; v[3] = _rotl(v[3], 21) ^ v[0]                          # noqa: E702
        v[2] = (v[2] + v[1]) & _M64; v[1] = _rotl(v[1], 17) ^ v[2]; v[2] = _rotl(v[2], 32)  # noqa: E702

    whole = len(data) - len(data) % 8
    for i in range(0, whole, 8):
        (m,) = struct.unpack_from("<Q", data, i)
        v[3] ^= m
        rnd()
        rnd()
        v[0] ^= m
    b = (len(data) & 0xFF) << 56 | int.from_bytes(data[whole:], "little")
    v[3] ^= b
    rnd()
    rnd()
    v[0] ^= b
    v[2] ^= 0xFF
    for _ in range(4):
        rnd()
    return v[0] ^ v[1] ^ v[2] ^ v[3]
