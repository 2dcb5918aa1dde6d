# SPDX-License-Identifier: MIT
"""The firmware's shape: the servo core's functions stay short enough to read
in one sitting, the crypto folder depends on nothing of the project (no
folder cycle), and every command of protocol.toml has its handler and its row
in the generated command table."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from torqueloop.spec import protocol as P

FW = Path(__file__).resolve().parent.parent / "firmware"
#: the longest C function the servo core may hold, lines from its signature to its closing brace
MAX_FUNCTION_LINES = 80


def functions(text: str) -> list[tuple[str, int]]:
    """(name, lines) of every function defined in C ``text``, whose body opens
    with a ``{`` and closes with a ``}`` alone at column 0 (the project's style)."""
    out, lines = [], text.splitlines()
    for i, ln in enumerate(lines):
        if ln != "{" or i == 0:
            continue
        start = i - 1
        while start > 0 and not re.match(r"[A-Za-z_]", lines[start]):   # a signature spread over lines
            start -= 1
        names = [n for n in re.findall(r"(\w+)\s*\(", lines[start]) if not n.startswith("__")]
        end = next(j for j in range(i, len(lines)) if lines[j] == "}")
        out.append((names[0] if names else f"line {start + 1}", end - start + 1))
    return out


def test_the_counter_counts() -> None:
    src = ("static int f(int x)\n{\n    return x;\n}\nvoid g(int a,\n       int b)\n{\n    (void)a;\n}\n"
           "static inline __attribute__((always_inline)) int h(void)\n{\n    return 0;\n}\n")
    assert functions(src) == [("f", 4), ("g", 5), ("h", 4)]


@pytest.mark.parametrize("path", sorted((FW / "servo").glob("*.[ch]")), ids=lambda p: p.name)
def test_servo_functions_are_short(path: Path) -> None:
    long = [(n, k) for n, k in functions(path.read_text()) if k > MAX_FUNCTION_LINES]
    assert not long, f"{path.name}: functions over {MAX_FUNCTION_LINES} lines: {long}"


def test_crypto_includes_no_project_header() -> None:
    own = {p.name for p in (FW / "crypto").glob("*.h")}
    for p in sorted((FW / "crypto").glob("*.[ch]")):
        for inc in re.findall(r'#include\s+"([^"]+)"', p.read_text()):
            assert inc in own, f"crypto/{p.name} includes {inc}: crypto/ must stand alone"


def test_every_command_has_its_handler_and_row() -> None:
    commands_c = (FW / "servo" / "commands.c").read_text()
    table = (FW / "protocol" / "tl_protocol.h").read_text()
    for c in P.COMMANDS.values():
        assert re.search(rf"static uint8_t {c.handler}\(tl_servo_t \*s", commands_c), f"{c.name}: no {c.handler}"
        assert f"X(TLP_CMD_{c.name}, {c.handler}," in table, f"{c.name}: no row in TLP_COMMAND_TABLE"
