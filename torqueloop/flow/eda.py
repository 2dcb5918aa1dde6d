# SPDX-License-Identifier: MIT
"""Lint, synthesis and formal-equivalence flows over the HDL manifest.

Used by torqueloop/flow/lint.py (make lint) and scripts/synth.py (make synth).  Each
function returns (ok, message) instead of raising, so one report lists every
problem.  All outputs go under build/.
"""

from __future__ import annotations

import json
import re
import shutil
import subprocess
from dataclasses import dataclass
from pathlib import Path
from typing import Iterable, Mapping

from torqueloop.flow import tools
from torqueloop.flow.manifest import REPO_ROOT, Core
from torqueloop.spec.regmap import BUS_REQ, BUS_RSP, BusField

BUILD = REPO_ROOT / "build"


@dataclass
class Result:
    ok: bool
    what: str
    detail: str = ""


def _run(cmd: list[str], cwd: Path | None = None, log: Path | None = None) -> tuple[int, str]:
    proc = subprocess.run(cmd, cwd=cwd, capture_output=True, text=True)
    out = proc.stdout + proc.stderr
    if log is not None:
        log.parent.mkdir(parents=True, exist_ok=True)
        log.write_text(" ".join(cmd) + "\n\n" + out)
    return proc.returncode, out


def _rel(p: Path) -> str:
    """Path as Yosys scripts name it: relative to the repo when inside it."""
    try:
        return str(p.relative_to(REPO_ROOT))
    except ValueError:
        return str(p)


# --- Verilator -Wall -----------------------------------------------------------

def verilator_lint(c: Core, params: Mapping[str, int] | None = None) -> Result:
    """verilator --lint-only -Wall: any warning fails (waivers are local /* verilator lint_off */)."""
    exe = shutil.which(tools.verilator())
    if exe is None:
        return Result(False, f"verilator lint {c.name}", "verilator not on PATH (run make setup)")
    params = params if params is not None else c.synth_params
    cmd = [exe, "--lint-only", "-Wall", "--top-module", c.top]
    cmd += [f"-G{k}={v}" for k, v in params.items()]
    cmd += [f"-I{d}" for d in c.include_dirs]
    cmd += [str(p) for p in c.verilog_sources]
    rc, out = _run(cmd, cwd=REPO_ROOT, log=BUILD / "lint" / c.name / "verilator.log")
    ok = rc == 0 and "%Warning" not in out and "%Error" not in out
    return Result(ok, f"verilator -Wall {c.name}", out.strip())


# --- GHDL analysis ----------------------------------------------------------------

def ghdl_analyse(c: Core) -> Result:
    """ghdl -a --std=08 then elaborate, with warnings shown."""
    work = BUILD / "lint" / c.name / "ghdl"
    work.mkdir(parents=True, exist_ok=True)
    out_all = []
    for src in c.vhdl:
        rc, out = _run(["ghdl", "-a", "--std=08", f"--workdir={work}", str(src)], cwd=REPO_ROOT)
        out_all.append(out)
        if rc != 0:
            return Result(False, f"ghdl -a {c.name}", out.strip())
    rc, out = _run(["ghdl", "-e", "--std=08", f"--workdir={work}", c.top], cwd=work)
    out_all.append(out)
    text = "\n".join(o for o in out_all if o.strip())
    # GHDL warns about Quartus attributes it does not know; that is expected.
    real_warnings = [l for l in text.splitlines()
                     if "warning" in l and "altera_attribute" not in l]
    return Result(rc == 0 and not real_warnings, f"ghdl --std=08 {c.name}", text.strip())


# --- VHDL -> Verilog for Yosys ----------------------------------------------------------

def ghdl_to_verilog(c: Core, params: Mapping[str, int], out: Path) -> tuple[bool, str]:
    """Synthesise the VHDL twin with GHDL into a Verilog netlist Yosys can read."""
    out.parent.mkdir(parents=True, exist_ok=True)
    cmd = ["ghdl", "synth", "--std=08", "--out=verilog"]
    cmd += [f"-g{k}={v}" for k, v in params.items()]
    cmd += [str(p) for p in c.vhdl] + ["-e", c.top]
    proc = subprocess.run(cmd, cwd=REPO_ROOT, capture_output=True, text=True)
    if proc.returncode != 0:
        return False, proc.stderr
    out.write_text(pack_bus_records(_fix_ghdl_wide_constants(proc.stdout), c.top))
    return True, proc.stderr


#: record ports of the VHDL twins -> their fields; the Verilog twin carries
#: each as one vector of the same name (regmap.vh's TL_BUS_* layout)
BUS_BUNDLES: dict[str, tuple[BusField, ...]] = {"bus_req": BUS_REQ, "bus_rsp": BUS_RSP}

_PORT = re.compile(r"^\s*\(?\s*(input|output)\s+(?:\[(\d+):0\]\s+)?(\w+)\s*(,|\);)\s*$")


def pack_bus_records(text: str, top: str) -> str:
    """GHDL flattens a record port into one port per field (``bus_req_stb``,
    ``bus_req_idx`` ...); give the top module the Verilog twin's port instead,
    one vector per record in the field layout of the register map's bus
    (torqueloop.spec.regmap.BUS_REQ / BUS_RSP), so equiv_make pairs the ports
    by name.  The fields stay as wires of their old names, so the netlist
    body is untouched.  A module without record ports is returned as is."""
    lines = text.split("\n")
    try:
        start = lines.index(f"module {top}")
    except ValueError:
        return text
    ports: list[tuple[str, int, str]] = []
    end = start + 1
    while True:
        m = _PORT.match(lines[end])
        if m is None:
            return text          # not the header layout this was written for: leave it
        ports.append((m.group(1), int(m.group(2)) + 1 if m.group(2) else 1, m.group(3)))
        if m.group(4) == ");":
            break
        end += 1
    names = {n for _, _, n in ports}
    bundles = {b: fs for b, fs in BUS_BUNDLES.items() if all(f"{b}_{f.name}" in names for f in fs)}
    if not bundles:
        return text
    fields = {f"{b}_{f.name}": (b, f) for b, fs in bundles.items() for f in fs}
    header: list[str] = []
    body: list[str] = []
    for direction, width, name in ports:
        if name in fields:
            b, f = fields[name]
            rng = f"[{f.width - 1}:0] " if f.width > 1 else ""
            sl = f"[{f.msb}:{f.lsb}]" if f.width > 1 else f"[{f.lsb}]"
            body.append(f"  wire {rng}{name};")
            body.append(f"  assign {name} = {b}{sl};" if direction == "input" else f"  assign {b}{sl} = {name};")
            continue
        header.append(f"{direction} {f'[{width - 1}:0] ' if width > 1 else ''}{name}")
    for b, fs in bundles.items():
        direction = next(d for d, _, n in ports if n == f"{b}_{fs[0].name}")
        header.append(f"{direction} [{fs[-1].msb}:0] {b}")
    new = [f"module {top}", "  (" + ",\n   ".join(header) + ");", *body]
    return "\n".join(lines[:start] + new + lines[end + 1:])


def _fix_ghdl_wide_constants(text: str) -> str:
    """GHDL 2.0 writes constants wider than 32 bits as quoted bit strings
    ("0101..."), which Verilog reads as ASCII text; make them sized binary
    literals.  Only strings made purely of 0/1 (and x/z) are touched."""
    return re.sub(r'"([01xz]{33,})"', lambda m: f"{len(m.group(1))}'b{m.group(1)}", text)


# --- Yosys -------------------------------------------------------------------------------

def _yosys(script: str, log: Path) -> tuple[int, str]:
    log.parent.mkdir(parents=True, exist_ok=True)
    script_file = log.with_suffix(".ys")
    script_file.write_text(script)
    return _run(["yosys", "-q", "-l", str(log), "-s", str(script_file)], cwd=REPO_ROOT)


def _incdirs(c: Core) -> str:
    return " ".join(f"-I{_rel(d)}" for d in c.include_dirs)


def _read_verilog_cmds(c: Core, params: Mapping[str, int]) -> str:
    files = " ".join(_rel(p) for p in c.verilog_sources)
    chparams = " ".join(f"-chparam {k} {v}" for k, v in params.items())
    return f"read_verilog -defer {_incdirs(c)} {files}\nhierarchy -check -top {c.top} {chparams}\n"


def yosys_check(c: Core) -> Result:
    """Generic Yosys synthesis with -check: no latches inferred, no undriven or multiply driven nets."""
    log = BUILD / "lint" / c.name / "yosys.log"
    script = (_read_verilog_cmds(c, c.synth_params) + f"synth -top {c.top}\ncheck -assert\n"
              + "select -assert-none t:$dlatch t:$adlatch t:$_DLATCH_*\n")
    rc, out = _yosys(script, log)
    text = log.read_text() if log.exists() else out
    latches = re.findall(r"Latch inferred for signal.*", text)
    ok = rc == 0 and not latches
    return Result(ok, f"yosys synth -check {c.name}", (out + "\n".join(latches)).strip())


def equivalence(c: Core, vhdl_override: Iterable[Path] | None = None,
                seq: int = 4, work: Path | None = None) -> Result:
    """Prove the VHDL twin equivalent to the Verilog core for all inputs, all time.

    The VHDL is synthesised by GHDL to Verilog; both are flattened and
    matched by Yosys ``equiv_make`` (state registers matched by name - the
    twins use the same internal signal names), then ``equiv_simple`` and
    ``equiv_induct`` prove every matched point by induction.  Initial values
    are honoured and asynchronous resets converted with ``async2sync``.
    """
    params = c.synth_params
    work = work or BUILD / "equiv" / c.name
    gate_v = work / "vhdl_twin.v"
    src = c if vhdl_override is None else Core(c.name, c.top, c.verilog, tuple(vhdl_override))
    ok, msg = ghdl_to_verilog(src, params, gate_v)
    if not ok:
        return Result(False, f"equivalence {c.name}", "ghdl synth failed:\n" + msg)
    script = (
        _read_verilog_cmds(c, params)
        + f"proc\nflatten\nopt_clean\nrename {c.top} gold\ndesign -stash gold\n"
        + f"read_verilog {_rel(gate_v)}\nhierarchy -check -top {c.top}\n"
        + f"proc\nflatten\nopt_clean\nrename {c.top} gate\ndesign -stash gate\n"
        + "design -copy-from gold -as gold gold\ndesign -copy-from gate -as gate gate\n"
        + "memory_map\nopt_clean\n"
        + "async2sync\n"
        + "equiv_make gold gate equiv\nhierarchy -top equiv\n"
        + f"equiv_simple -seq {seq}\nequiv_induct -seq {seq}\n"
        + "equiv_status -assert\n"
    )
    rc, out = _yosys(script, work / "equiv.log")
    log_text = (work / "equiv.log").read_text() if (work / "equiv.log").exists() else out
    status = re.findall(r"Found \d+ \$equiv cells.*|Of those cells \d+ are proven and \d+ are unproven.*|Equivalence successfully proven!", log_text)
    return Result(rc == 0, f"equivalence VHDL == Verilog {c.name}",
                  ("; ".join(status) if rc == 0 else out.strip()[-3000:]))


def prove_properties(c: Core) -> list[Result]:
    """Prove each property wrapper of the core with Yosys SAT (k-induction).

    The wrapper is read with ``read_verilog -formal`` together with the
    core's sources; ``sat -tempinduct -prove-asserts`` must close within the
    wrapper's depth, with the reset input (if named) high in the first step.
    """
    results = []
    for chk in c.formal:
        files = " ".join(_rel(p) for p in (*c.verilog_sources, chk.file))
        reset = f"-set-at 1 {chk.reset} 1 " if chk.reset else ""
        script = (
            # memory_map: sat cannot import memories; model them as flip-flops.
            f"read_verilog -formal {_incdirs(c)} {files}\nprep -top {chk.top}\nflatten\nmemory_map\nopt_clean\nasync2sync\n"
            f"sat -tempinduct -prove-asserts {reset}-seq 1 -maxsteps {chk.depth} -verify\n"
        )
        log = BUILD / "formal" / c.name / f"{chk.top}.log"
        rc, out = _yosys(script, log)
        text = log.read_text() if log.exists() else out
        results.append(Result(rc == 0, f"formal {c.name}: {chk.top}",
                              "proven by induction" if rc == 0 else out.strip()[-3000:]))
    return results


# --- Cyclone V resource estimate ---------------------------------------------------------

def synth_cyclonev(c: Core, params: Mapping[str, int] | None = None, tag: str = "") -> dict:
    """Yosys synth_intel_alm -family cyclonev: cell counts and longest path.

    The longest path is taken with flip-flops and I/O buffers cut out, so it
    counts the ALM cells (LUTs and carry-chain cells) between two registers
    or a port and a register: a logic-depth estimate, not a timing figure.
    """
    params = params if params is not None else c.synth_params
    name = c.name + (f"_{tag}" if tag else "")
    work = BUILD / "synth" / name
    script = (
        _read_verilog_cmds(c, params)
        + f"synth_intel_alm -family cyclonev -top {c.top} -noiopad\n"
        + "tee -o {stat} stat\n".format(stat=_rel(work / "stat.txt"))
        + "select -set comb * t:MISTRAL_FF %d\n"
        + "tee -o {ltp} ltp @comb\n".format(ltp=_rel(work / "ltp.txt"))
        + f"write_json {_rel(work / 'netlist.json')}\n"
    )
    rc, out = _yosys(script, work / "synth.log")
    if rc != 0:
        return {"core": name, "error": out.strip()[-2000:]}
    stat = (work / "stat.txt").read_text()
    cells = {m.group(1): int(m.group(2)) for m in re.finditer(r"^\s+(MISTRAL_\w+|\$\w+)\s+(\d+)\s*$", stat, re.M)}
    mem_bits = int(m.group(1)) if (m := re.search(r"Number of memory bits:\s+(\d+)", stat)) else 0
    ltp_txt = (work / "ltp.txt").read_text()
    depth = int(m.group(1)) if (m := re.search(r"Longest topological path in \S+ \(length=(\d+)\)", ltp_txt)) else 0
    levels = lut_levels(work / "netlist.json", c.top)
    luts = sum(v for k, v in cells.items() if k.startswith("MISTRAL_ALUT") and "ARITH" not in k)
    m10k = cells.get("MISTRAL_M10K", 0)
    mlab = cells.get("MISTRAL_MLAB", 0)
    return {
        "core": name,
        "params": dict(params),
        "luts": luts,
        "carry_cells": cells.get("MISTRAL_ALUT_ARITH", 0),
        "ffs": cells.get("MISTRAL_FF", 0),
        "m10k": m10k,
        "mlab": mlab,
        "memory_bits": mem_bits,
        "dsp": cells.get("MISTRAL_MUL27X27", 0) + cells.get("MISTRAL_MUL18X18", 0) + cells.get("MISTRAL_MUL9X9", 0),
        "longest_path_cells": depth,
        "lut_levels": levels,
        "cells": cells,
    }


#: cells whose outputs start a new timing path (registers and block RAMs with
#: registered reads).  Yosys maps multipliers to unregistered DSP cells, so
#: MISTRAL_MUL* stays combinational here (one level, an under-estimate of
#: its delay).
_SEQUENTIAL = ("MISTRAL_FF", "MISTRAL_M10K", "MISTRAL_MLAB")


def lut_levels(netlist_json: Path, top: str) -> int:
    """Logic depth in LUT levels between registers/ports of a synthesised netlist.

    Yosys ``ltp`` counts every carry-chain cell as a level, so a 32-bit adder
    reads as 32 levels although its carry ripple is the fast dedicated
    route.  Here a cell entered through its carry input (CI) adds no level;
    any other entry (a LUT, or an adder cell entered at its data inputs)
    adds one.
    """
    mod = json.loads(netlist_json.read_text())["modules"][top]
    cells = mod["cells"]
    driver: dict[int, str] = {}
    for name, cell in cells.items():
        for port, bits in cell["connections"].items():
            if cell["port_directions"].get(port) == "output":
                for b in bits:
                    if isinstance(b, int):
                        driver[b] = name
    memo: dict[str, int] = {}

    def depth(name: str, stack: set[str]) -> int:
        if name in memo:
            return memo[name]
        cell = cells[name]
        if cell["type"].startswith(_SEQUENTIAL) or name in stack:
            return 0
        stack.add(name)
        best = 1
        for port, bits in cell["connections"].items():
            if cell["port_directions"].get(port) != "input":
                continue
            cost = 0 if port == "CI" else 1
            for b in bits:
                d = driver.get(b) if isinstance(b, int) else None
                if d is not None and not cells[d]["type"].startswith(_SEQUENTIAL):
                    best = max(best, depth(d, stack) + cost)
        stack.discard(name)
        memo[name] = best
        return best

    import sys
    old = sys.getrecursionlimit()
    sys.setrecursionlimit(max(old, 20000))
    try:
        comb = [n for n, c in cells.items() if not c["type"].startswith(_SEQUENTIAL)]
        return max((depth(n, set()) for n in comb), default=0)
    finally:
        sys.setrecursionlimit(old)


def write_synth_table(rows: list[dict], out_dir: Path = BUILD / "synth") -> Path:
    out_dir.mkdir(parents=True, exist_ok=True)
    (out_dir / "resources.json").write_text(json.dumps(rows, indent=2))
    lines = [
        "| core | LUTs | carry | FFs | M10K | MLAB | mem bits | DSP | LUT levels | ltp cells |",
        "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|",
    ]
    for r in rows:
        if "error" in r:
            lines.append(f"| {r['core']} | synthesis failed | | | | | | | | |")
            continue
        lines.append(
            f"| {r['core']} | {r['luts']} | {r['carry_cells']} | {r['ffs']} | {r['m10k']} | {r['mlab']} "
            f"| {r['memory_bits']} | {r['dsp']} | {r['lut_levels']} | {r['longest_path_cells']} |"
        )
    md = out_dir / "resources.md"
    md.write_text("\n".join(lines) + "\n")
    return md
