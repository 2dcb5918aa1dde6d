# SPDX-License-Identifier: MIT
"""Who may do what on the dashboard.

Two roles: ``watch`` sees everything and may press STOP (stopping is always
allowed, as on the board, which takes STOP and disable without the key);
``command`` may also enable, move, drive, step and set, save parameters.

On 127.0.0.1 (the default) the page needs no token, as the session server's
JSON-lines port needs none: whoever can reach a loopback port is a user of
this machine.  The page then answers only requests whose Host header names
the loopback address (a web site that points its own name at 127.0.0.1
cannot use the dashboard from a browser here) and WebSockets opened by a
page of its own origin.  On any other address every request needs a token:
the server makes a fresh pair at each start and prints the two URLs, or
reads them from a token file (``--http-tokens FILE``: lines ``command
TOKEN`` and ``watch TOKEN``, the file private to its owner); a token file
makes tokens necessary on the loopback address too.

The link key never reaches a page: it stays in the session server's
client, and no message to a page carries it or anything derived from it.
"""

from __future__ import annotations

import hmac
import os
import secrets
import stat
from dataclasses import dataclass
from pathlib import Path

ROLES = ("watch", "command")
#: what a watcher may ask besides watching
WATCH_OPS = frozenset({"stop", "params"})
LOOPBACK = ("127.0.0.1", "localhost", "::1")


class TokenFileError(ValueError):
    pass


def new_tokens() -> dict[str, str]:
    return {role: secrets.token_urlsafe(18) for role in ROLES}


def read_token_file(path: Path) -> dict[str, str]:
    """``{role: token}`` from a file of ``ROLE TOKEN`` lines (``#`` comments);
    refused when others may read it or a token is short."""
    try:
        st = path.stat()
        text = path.read_text()
    except OSError as e:
        raise TokenFileError(f"token file {path}: {e.strerror or e}") from None
    if stat.S_IMODE(st.st_mode) & 0o077:
        raise TokenFileError(f"token file {path} is readable by others (mode {stat.S_IMODE(st.st_mode):o}): "
                             f"chmod 600 {path}")
    out: dict[str, str] = {}
    for n, line in enumerate(text.splitlines(), 1):
        line = line.split("#", 1)[0].strip()
        if not line:
            continue
        parts = line.split()
        if len(parts) != 2 or parts[0] not in ROLES:
            raise TokenFileError(f"token file {path}, line {n}: write `command TOKEN` or `watch TOKEN`")
        if len(parts[1]) < 16:
            raise TokenFileError(f"token file {path}, line {n}: a token of at least 16 characters")
        out[parts[0]] = parts[1]
    if not out:
        raise TokenFileError(f"token file {path} holds no token")
    if out.get("command") is not None and out.get("command") == out.get("watch"):
        raise TokenFileError(f"token file {path}: the watch token must differ from the command token")
    return out


def write_token_file(path: Path, tokens: dict[str, str]) -> None:
    fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o600)
    with os.fdopen(fd, "w") as f:
        for role, tok in tokens.items():
            f.write(f"{role} {tok}\n")


@dataclass(frozen=True)
class Access:
    """``tokens``: {role: token}; empty: no token needed (loopback only)."""
    tokens: dict[str, str]
    host: str
    port: int

    @property
    def open(self) -> bool:
        return not self.tokens

    def role(self, token: str | None) -> str | None:
        """The role a token gives (``command`` for everyone on an open loopback page), or None."""
        if self.open:
            return "command"
        if not token:
            return None
        for role in ("command", "watch"):
            want = self.tokens.get(role)
            if want and hmac.compare_digest(want.encode(), token.encode()):
                return role
        return None

    def host_ok(self, host_header: str | None) -> bool:
        """On an open (loopback) page, the request's Host names the loopback address."""
        if not self.open:
            return True
        if not host_header:
            return False
        h = host_header.strip().lower()
        name = h[1:h.index("]")] if h.startswith("[") and "]" in h else h.rsplit(":", 1)[0] if ":" in h else h
        return name in LOOPBACK

    @staticmethod
    def may(role: str, op: str) -> bool:
        return role == "command" or op in WATCH_OPS
