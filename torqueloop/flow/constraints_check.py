# SPDX-License-Identifier: MIT
"""Consistency checks of the DE0-CV constraints (``python -m torqueloop.flow constraints``; exit 1 if any fails).

Quartus is not available where the project is built and tested, so the
Quartus project must be right by construction; these checks read the
committed .qsf and .sdc back (with their own parsers, not the generators)
and compare them with the board top as Yosys reads it, the pin table, the
board's pin data and the HDL manifest:

  - the repo's board pin copy equals the reference pin table it was made from (when a developer has it);
  - the pin table is consistent (no pin twice, header numbers, directions);
  - every top-level port is in the pin table with its direction and width;
  - every port bit has exactly one location, the board's, and the board's
    I/O standard in the .qsf; no location is used twice; device, family and
    top are right; the DEV_CLRN option is off;
  - the .qsf's source files are the board top's manifest sources, include
    every file of the SoC core, exist, and elaborate (Yosys hierarchy -check);
    none is a vendor primitive's interface (rtl/lint_only/, which Quartus
    must take from itself), and with the table's [top_parameters] (the
    configuration flash through the ASMI block) the design elaborates with
    only those primitives left as black boxes;
  - the .sdc constrains CLOCK_50 at the table's period and names only ports
    that exist.

That the generated files are in step with pins.toml is the staleness gate's
job (``python -m torqueloop.flow gen --check``), as for every generated file.
"""

from __future__ import annotations

import re
import sys
import time
from dataclasses import dataclass
from pathlib import Path

from torqueloop.flow import board_files as board, quartus
from torqueloop.flow.manifest import REPO_ROOT, Core, load_manifest


@dataclass
class Check:
    name: str
    ok: bool
    detail: str = ""
    skipped: bool = False


def _result(name: str, problems: list[str]) -> Check:
    return Check(name, not problems, "\n".join(problems))


def check_board_copy(ours: Path = board.BOARD_PINS_CSV,
                     shared: Path = board.SHARED_BOARD_PINS_CSV) -> Check:
    name = "board pin copy == the reference pin table"
    if not shared.exists():
        return Check(name, True, f"{shared} not present (repo used on its own): comparison skipped", skipped=True)
    return _result(name, board.compare_board_tables(board.load_board_pins(ours), board.load_board_pins(shared)))


def check_pin_table(table: board.PinTable, board_pins: dict[str, board.BoardPin]) -> Check:
    return _result("pin table consistent with the board", board.validate(table, board_pins))


def top_headers(table: board.PinTable) -> list[Path]:
    """The `define headers (.vh) of the board top's manifest core, in order."""
    core = load_manifest().get(table.board.top)
    return [p for p in core.verilog if p.suffix == ".vh"] if core else []


def check_top_ports(table: board.PinTable, top_v: Path = board.TOP_V) -> Check:
    """Every port of the top in the table with the same direction and width, and back."""
    name = f"top-level ports of {top_v.name} == pin table ports"
    try:
        ports = board.top_ports(top_v, table.board.top, top_headers(table))
    except (RuntimeError, KeyError) as e:
        return Check(name, False, str(e))
    problems = []
    want = {p.name: (p.dir, p.width) for p in table.ports}
    for n, (d, w) in ports.items():
        if n not in want:
            problems.append(f"port {n} ({d}, width {w}) has no entry in constraints/pins.toml: it would get no pin")
        elif want[n] != (d, w):
            problems.append(f"port {n}: top has ({d}, width {w}), pin table ({want[n][0]}, width {want[n][1]})")
    for n in want:
        if n not in ports:
            problems.append(f"pin table port {n} is not a port of {table.board.top}")
    return _result(name, problems)


def check_qsf_pins(table: board.PinTable, board_pins: dict[str, board.BoardPin], qsf_text: str) -> Check:
    """Locations, I/O standards, pull-ups and device settings of the .qsf."""
    name = "qsf: every port bit has the board's pin and I/O standard, no pin twice"
    try:
        s = board.parse_qsf(qsf_text)
    except (ValueError, KeyError, IndexError) as e:
        return Check(name, False, f"unreadable .qsf: {e}")
    problems = []
    b = table.board
    expect_globals = {"FAMILY": b.family, "DEVICE": b.device, "TOP_LEVEL_ENTITY": b.quartus_top,
                      "ENABLE_DEVICE_WIDE_RESET": "OFF"}
    for k, v in expect_globals.items():
        if s.globals.get(k) != [v]:
            problems.append(f"{k} is {s.globals.get(k)}, expected [{v!r}]")
    bits = {bit for _, bit in table.port_bits()}
    by_location: dict[str, str] = {}
    for bit in sorted(bits):
        locs = s.locations.get(bit, [])
        if len(locs) != 1:
            problems.append(f"{bit}: {len(locs)} location assignments")
            continue
        expected = f"PIN_{board_pins[bit].pin}" if bit in board_pins else None
        if locs[0] != expected:
            problems.append(f"{bit}: location {locs[0]}, board table says {expected}")
        if locs[0] in by_location:
            problems.append(f"location {locs[0]} used twice: {by_location[locs[0]]} and {bit}")
        by_location[locs[0]] = bit
        std = s.instance.get(("IO_STANDARD", bit), [])
        if std != [board_pins[bit].io_standard if bit in board_pins else b.io_standard]:
            problems.append(f"{bit}: IO_STANDARD {std}, expected {board_pins[bit].io_standard!r}")
    for target in s.locations:
        if target not in bits:
            problems.append(f"location assigned to {target}, which is not a port bit of the top")
    for (aname, target), vals in s.instance.items():
        if target not in bits:
            problems.append(f"{aname} assigned to {target}, which is not a port bit of the top")
    pulled = {t for (a, t), v in s.instance.items() if a == "WEAK_PULL_UP_RESISTOR" and v == ["ON"]}
    want_pulled = {g.signal for g in table.gpio if g.pull_up}
    if pulled != want_pulled:
        problems.append(f"weak pull-ups on {sorted(pulled)}, pin table wants {sorted(want_pulled)}")
    return _result(name, problems)


def _qsf_files(s: board.QsfSettings, kind: str, project_dir: Path) -> list[Path]:
    return [(project_dir / v).resolve() for v in s.globals.get(kind, [])]


def check_qsf_sources(table: board.PinTable, qsf_text: str, cores: dict[str, Core] | None = None,
                      project_dir: Path = board.QUARTUS_DIR, elaborate: bool = True) -> Check:
    """The project's sources: the top's manifest list, all SoC files, elaborating."""
    name = "qsf: sources = board top's manifest list, every SoC file in, design elaborates"
    cores = cores if cores is not None else load_manifest()
    s = board.parse_qsf(qsf_text)
    files = _qsf_files(s, "VERILOG_FILE", project_dir)
    problems = [f"{f} (named in the .qsf) does not exist" for f in files if not f.is_file()]
    top = cores.get(table.board.quartus_top)
    soc = cores.get(table.board.soc_core)
    if top is None:
        problems.append(f"core {table.board.quartus_top} is not in rtl/manifest.toml")
    else:
        listed = [p.resolve() for p in quartus.project_sources(top.verilog) if p.suffix != ".vh"]
        problems += [f"{_rel(f)} is a vendor primitive's interface (rtl/lint_only/): Quartus has the primitive"
                     for f in files if quartus.is_lint_only(f)]
        if files != listed:
            problems.append("VERILOG_FILE list differs from rtl/manifest.toml core "
                            f"{top.name}: qsf {[_rel(f) for f in files]}, manifest {[_rel(f) for f in listed]}")
    if soc is None:
        problems.append(f"SoC core {table.board.soc_core} is not in rtl/manifest.toml")
    else:
        missing = [p for p in soc.verilog if p.suffix != ".vh" and p.resolve() not in files]
        problems += [f"SoC source {_rel(p)} is not in the Quartus project" for p in missing]
    for kind in ("SDC_FILE",):
        for f in _qsf_files(s, kind, project_dir):
            if not f.is_file():
                problems.append(f"{kind} {f} does not exist")
    if not s.globals.get("SDC_FILE"):
        problems.append("no SDC_FILE in the .qsf")
    if elaborate and files and not problems:
        # The board top, not the Quartus top: its $readmemh images exist only
        # after a firmware build (make lint's strict front end elaborates that one).
        ok, out = board.elaborate(files, table.board.top,
                                  include_dirs=_qsf_files(s, "SEARCH_PATH", project_dir))
        if not ok:
            problems.append("Yosys cannot elaborate the project's files:\n" + out[-2000:])
        elif top is not None and table.top_parameters:
            stubs = [p for p in top.verilog if quartus.is_lint_only(p)]
            ok, out = board.elaborate(files + stubs, table.board.top,
                                      include_dirs=_qsf_files(s, "SEARCH_PATH", project_dir),
                                      params=dict(table.top_parameters))
            if not ok:
                problems.append("Yosys cannot elaborate the project's files with [top_parameters] "
                                f"{dict(table.top_parameters)} and the vendor primitives' interfaces:\n" + out[-2000:])
    return _result(name, problems)


def _rel(p: Path) -> str:
    try:
        return str(p.resolve().relative_to(REPO_ROOT))
    except ValueError:
        return str(p)


def check_sdc(table: board.PinTable, sdc_text: str, top_port_bits: set[str] | None = None) -> Check:
    """The clock and that every port the .sdc names exists."""
    name = "sdc: CLOCK_50 at the board period, only existing ports named"
    problems = []
    bits = top_port_bits if top_port_bits is not None else {b for _, b in table.port_bits()}
    for n in board.sdc_port_names(sdc_text):
        if not _sdc_matches(n, bits):
            problems.append(f"get_ports {n}: no such port of the top")
    clk = next(p for p in table.ports if p.timing == "clock")
    want = f"create_clock -name {clk.name} -period {table.board.clock_period_ns:.3f} [get_ports {{{clk.name}}}]"
    if want not in sdc_text.splitlines():
        problems.append(f"missing: {want}")
    for line in sdc_text.splitlines():
        if line.startswith("set_false_path") and clk.name in board.sdc_port_names(line):
            problems.append(f"the clock port is cut by a false path: {line}")
    if "derive_clock_uncertainty" not in sdc_text.split():
        problems.append("missing: derive_clock_uncertainty")
    from torqueloop.spec import regs

    if round(1e9 / table.board.clock_period_ns) != regs.CLK_HZ:
        problems.append(f"clock period {table.board.clock_period_ns} ns is not the SoC's CLK_HZ = {regs.CLK_HZ} Hz")
    return _result(name, problems)


def _sdc_matches(pattern: str, bits: set[str]) -> bool:
    """Does an SDC port pattern (exact name, or with * wildcards) name at least one port bit?"""
    if "*" not in pattern and "?" not in pattern:
        return pattern in bits
    rx = re.compile(re.escape(pattern).replace(r"\*", ".*").replace(r"\?", "."))
    return any(rx.fullmatch(b) for b in bits)


def port_bits_of_top(table: board.PinTable, top_v: Path = board.TOP_V) -> set[str]:
    """Bit names of the top's ports as Yosys reads them ('KEY[0]', 'CLOCK_50')."""
    out = set()
    for n, (_, w) in board.top_ports(top_v, table.board.top, top_headers(table)).items():
        out |= {n} if w is None else {f"{n}[{i}]" for i in range(w)}
    return out


def run_all() -> list[Check]:
    table = board.load_pin_table()
    board_pins = board.load_board_pins()
    checks = [check_board_copy(), check_pin_table(table, board_pins), check_top_ports(table)]
    qsf = board.QSF.read_text() if board.QSF.exists() else ""
    sdc = board.SDC.read_text() if board.SDC.exists() else ""
    checks.append(check_qsf_pins(table, board_pins, qsf))
    checks.append(check_qsf_sources(table, qsf))
    try:
        top_bits: set[str] | None = port_bits_of_top(table)
    except (RuntimeError, KeyError):
        top_bits = None          # check_top_ports has reported it
    checks.append(check_sdc(table, sdc, top_bits) if top_bits is not None
                  else Check("sdc", False, "the top could not be read"))
    return checks


def main() -> int:
    t0 = time.monotonic()
    checks = run_all()
    for c in checks:
        mark = "skip" if c.skipped else ("ok  " if c.ok else "FAIL")
        print(f"[constraints] {mark} {c.name}" + (f"  ({c.detail})" if c.skipped else ""))
    failed = [c for c in checks if not c.ok]
    for c in failed:
        lines = c.detail.splitlines()
        more = f"\n... and {len(lines) - 40} more" if len(lines) > 40 else ""
        print(f"\n---- {c.name} ----\n" + "\n".join(lines[:40]) + more + "\n", file=sys.stderr)
    print(f"[constraints] {len(checks) - len(failed)} passed, {len(failed)} failed "
          f"in {time.monotonic() - t0:.1f} s")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
