# SPDX-License-Identifier: MIT
"""Quartus safety of the Verilog, checked by construction in make lint.

Nobody here can run Quartus, so the patterns that work in Icarus, Verilator
and Yosys but are not what Intel documents for Quartus are refused before
they land (Intel, "Quartus Prime Standard Edition User Guide:
Design Recommendations", chapter Recommended HDL Coding Styles):

* include: a file that uses the register map's `TL_* names includes
  ``regmap.vh`` itself, before the first use, instead of relying on the
  compile order of the project's file list;
* memory: every memory array of the synthesised RTL (rtl/) names the Intel
  inference template it follows ("Intel template: ..." in a comment before
  it) and keeps the template's shape - written and read only in clocked
  always blocks (unless the template is an asynchronous read, which goes to
  MLAB or registers), no reset, at most two ports (always blocks), one write
  address per block, initialised only by $readmemh or a for loop in an
  initial block;
* system functions: synthesised code calls none but $clog2, $signed,
  $unsigned and, in an initial block, $readmemh.

The check reads the text (comments and strings out, `ifdef branches taken as
Quartus sees them with no macro defined); it is a guard for the shapes this
project writes, not a Verilog parser - the strict front end (pyslang, in
torqueloop.flow.strict) parses.  ``python -m torqueloop.flow.hdl_rules`` runs it.
"""

from __future__ import annotations

import re
import sys
from dataclasses import dataclass
from pathlib import Path

from torqueloop.flow.checks import finish
from torqueloop.flow.manifest import REPO_ROOT, load_manifest

#: what synthesised code may call
ALLOWED_SYSTEM_FUNCTIONS = {"$clog2", "$signed", "$unsigned", "$readmemh"}
REGMAP_INCLUDE = '`include "regmap.vh"'


@dataclass(frozen=True)
class Finding:
    path: Path
    line: int
    rule: str
    text: str

    def __str__(self) -> str:
        try:
            rel = self.path.relative_to(REPO_ROOT)
        except ValueError:
            rel = self.path
        return f"{rel}:{self.line}: [{self.rule}] {self.text}"


# --- reading --------------------------------------------------------------------------------

def _blank(m: re.Match) -> str:
    """Keep line breaks (for line numbers), blank the rest."""
    return re.sub(r"[^\n]", " ", m.group(0))


def strip_comments(text: str) -> str:
    """Comments blanked (strings kept whole, a // inside one is no comment),
    line structure kept."""
    return re.sub(r'//[^\n]*|/\*.*?\*/|"(?:\\.|[^"\\])*"',
                  lambda m: m.group(0) if m.group(0).startswith('"') else _blank(m), text, flags=re.S)


def preprocess(text: str) -> str:
    """`ifdef / `ifndef / `else / `endif evaluated with no macro defined (as a
    Quartus project without VERILOG_MACRO sees them); dropped lines blanked."""
    lines = text.split("\n")
    stack: list[bool] = []          # is this branch taken
    out = []
    for line in lines:
        m = re.match(r"\s*`(ifdef|ifndef|else|endif|elsif)\b\s*(\w*)", line)
        if m:
            kw = m.group(1)
            if kw == "ifdef":
                stack.append(False)
            elif kw == "ifndef":
                stack.append(True)
            elif kw == "else" and stack:
                stack[-1] = not stack[-1]
            elif kw == "elsif" and stack:
                stack[-1] = False
            elif kw == "endif" and stack:
                stack.pop()
            out.append("")
            continue
        out.append(line if all(stack) else "")
    return "\n".join(out)


@dataclass
class Item:
    """One always / initial block or continuous assignment."""

    kind: str          # "clocked", "comb", "initial", "assign"
    start: int         # offset in the text
    body: str


def _match_block(text: str, i: int) -> int:
    """End offset of the statement starting at i (a begin..end block or up to ';')."""
    m = re.compile(r"\s*").match(text, i)
    i = m.end()
    if re.match(r"begin\b", text[i:]):
        depth = 0
        for t in re.finditer(r"\b(begin|end)\b", text[i:]):
            depth += 1 if t.group(1) == "begin" else -1
            if depth == 0:
                return i + t.end()
        return len(text)
    j = text.find(";", i)
    return len(text) if j < 0 else j + 1


def items(code: str) -> list[Item]:
    out = []
    for m in re.finditer(r"\b(always|initial|assign)\b", code):
        kw, i = m.group(1), m.end()
        if kw == "assign":
            j = code.find(";", i)
            out.append(Item("assign", m.start(), code[i:j + 1]))
            continue
        kind = "initial"
        if kw == "always":
            s = re.compile(r"\s*@\s*(\*|\()").match(code, i)
            if s is None:
                continue
            if s.group(1) == "(":
                depth, k = 0, s.end() - 1
                while k < len(code):
                    depth += {"(": 1, ")": -1}.get(code[k], 0)
                    k += 1
                    if depth == 0:
                        break
                sens = code[s.end() - 1:k]
                i = k
            else:
                sens, i = "*", s.end()
            kind = "clocked" if re.search(r"\b(posedge|negedge)\b", sens) else "comb"
        end = _match_block(code, i)
        out.append(Item(kind, m.start(), code[i:end]))
    return out


def _line(code: str, offset: int) -> int:
    return code.count("\n", 0, offset) + 1


# --- rules ----------------------------------------------------------------------------------

def check_include(path: Path, text: str) -> list[Finding]:
    code = strip_comments(text)
    use = re.search(r"`TL_\w+", code)
    if use is None:
        return []
    inc = re.search(r'`include\s+"regmap\.vh"', code)
    if inc is None:
        return [Finding(path, _line(code, use.start()), "include",
                        f"uses {use.group(0)} without {REGMAP_INCLUDE} (names must not depend on the compile order)")]
    if inc.start() > use.start():
        return [Finding(path, _line(code, use.start()), "include",
                        f"uses {use.group(0)} before {REGMAP_INCLUDE}")]
    return []


def check_system_functions(path: Path, text: str) -> list[Finding]:
    code = preprocess(strip_comments(text))
    found = []
    for m in re.finditer(r"\$[A-Za-z_]\w*", code):
        if m.group(0) not in ALLOWED_SYSTEM_FUNCTIONS:
            found.append(Finding(path, _line(code, m.start()), "system-function",
                                 f"{m.group(0)} in synthesised code (allowed: {', '.join(sorted(ALLOWED_SYSTEM_FUNCTIONS))})"))
    for it in items(code):
        if "$readmemh" in it.body and it.kind != "initial":
            found.append(Finding(path, _line(code, it.start), "system-function",
                                 "$readmemh outside an initial block"))
    return found


_MEM_DECL = re.compile(r"\breg\s*(?:\[[^\]]*\])?\s*(\w+)\s*\[[^\]]*\]\s*;")


def memories(code: str) -> list[tuple[str, int]]:
    """(name, offset) of every array (a reg with an unpacked dimension)."""
    code = re.sub(r"\(\*.*?\*\)", lambda m: _blank(m), code, flags=re.S)
    return [(m.group(1), m.start()) for m in _MEM_DECL.finditer(code)]


def check_memories(path: Path, text: str) -> list[Finding]:
    code = preprocess(strip_comments(text))
    found: list[Finding] = []
    mems = {n: off for n, off in memories(code)}
    if not mems:
        return []
    tmpl = re.search(r"Intel template:\s*(.*)", text)
    blocks = items(code)
    for name, off in mems.items():
        where = _line(code, off)
        if tmpl is None:
            found.append(Finding(path, where, "memory",
                                 f"memory {name} names no Intel inference template ('Intel template: ...' comment)"))
            continue
        async_ok = bool(re.search(r"asynchronous read", text[tmpl.start():tmpl.start() + 600], re.I))
        ref = re.compile(rf"\b{re.escape(name)}\s*\[")
        ports = 0
        for it in blocks:
            if not ref.search(it.body):
                continue
            line = _line(code, it.start)
            if it.kind in ("assign", "comb"):
                if not async_ok:
                    found.append(Finding(path, line, "memory",
                                         f"memory {name} read outside a clocked block (the template reads on the clock)"))
                continue
            if it.kind == "initial":
                if not re.search(r"\$readmemh|\bfor\b", it.body):
                    found.append(Finding(path, line, "memory",
                                         f"memory {name} initialised other than by $readmemh or a for loop"))
                continue
            ports += 1
            if re.search(r"\b\w*(rst|reset)\w*\b", it.body, re.I):
                found.append(Finding(path, line, "memory",
                                     f"memory {name} in a block with a reset (block RAM contents have none)"))
            writes = {re.sub(r"\s+", "", w.group(1))
                      for w in re.finditer(rf"\b{re.escape(name)}\s*\[([^\]]*)\](?:\s*\[[^\]]*\])?\s*<=", it.body)}
            if len(writes) > 1:
                found.append(Finding(path, line, "memory",
                                     f"memory {name} written at {len(writes)} addresses in one block "
                                     "(a priority between ports: the template has one always block per port)"))
        if ports > 2:
            found.append(Finding(path, where, "memory",
                                 f"memory {name} used by {ports} clocked blocks: a block RAM has two ports"))
    return found


# --- the tree -------------------------------------------------------------------------------

def project_files() -> tuple[list[Path], list[Path]]:
    """(every Verilog file of the manifest, the synthesised ones under rtl/)."""
    files: dict[Path, None] = {}
    for c in load_manifest().values():
        for p in c.verilog_sources:
            files[p] = None
        for f in c.formal:
            files[f.file] = None
    all_v = sorted(files)
    rtl = [p for p in all_v if (REPO_ROOT / "rtl") in p.parents]
    return all_v, rtl


def check(all_files: list[Path] | None = None, rtl_files: list[Path] | None = None) -> list[Finding]:
    if all_files is None or rtl_files is None:
        a, r = project_files()
        all_files = a if all_files is None else all_files
        rtl_files = r if rtl_files is None else rtl_files
    found: list[Finding] = []
    for p in all_files:
        found += check_include(p, p.read_text())
    for p in rtl_files:
        text = p.read_text()
        found += check_system_functions(p, text)
        found += check_memories(p, text)
    return found


def main() -> int:
    all_files, rtl_files = project_files()
    found = check(all_files, rtl_files)
    return finish("hdl-rules", found, f"Quartus-safety rules on {len(all_files)} files "
                                      f"({len(rtl_files)} synthesised): {len(found)} finding(s)")


if __name__ == "__main__":
    sys.exit(main())
