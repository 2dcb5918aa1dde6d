# SPDX-License-Identifier: MIT
"""The DE0-CV pin table (constraints/pins.toml) and what is generated from it.

One source, several products: the Quartus settings (.qsf), the timing
constraints (.sdc), the GPIO header block of the board top, its mirror for the
board test wrappers (the cable harness module) and the wiring table of
docs/hardware.md.  torqueloop.flow.generate writes them (through flow/quartus.py),
python -m torqueloop.flow constraints checks them; both go through this module.

The board's own pin data (FPGA location and I/O standard of each board
signal) is constraints/de0_cv_board_pins.csv, a copy of Terasic's DE0_CV.qsf
assignments kept in the repo, the one the project builds from.
"""

from __future__ import annotations

import csv
import io
import json
import os
import re
import shlex
import subprocess
import tempfile
import tomllib
from dataclasses import dataclass
from pathlib import Path

from torqueloop.flow.manifest import REPO_ROOT

CONSTRAINTS = REPO_ROOT / "constraints"
PINS_TOML = CONSTRAINTS / "pins.toml"
BOARD_PINS_CSV = CONSTRAINTS / "de0_cv_board_pins.csv"
SHARED_BOARD_PINS_CSV = REPO_ROOT.parent / "shared" / "board" / "de0_cv_pins.csv"
QSF = CONSTRAINTS / "de0_cv_top.qsf"
SDC = CONSTRAINTS / "de0_cv_top.sdc"
TOP_V = REPO_ROOT / "rtl" / "board" / "de0_cv_top.v"
#: The cable harness of the board's test wrappers (tb/de0_cv_top/de0_cv_top_tb.v,
#: torqueloop/sim/harness/rtl_loop_top.v): a generated module wiring the header bits to
#: nets named as the top's (gen_cable_module).
CABLE_V = REPO_ROOT / "torqueloop" / "sim" / "harness" / "de0_cv_cable.v"
HARDWARE_MD = REPO_ROOT / "docs" / "hardware.md"
#: The Quartus project folder; the .qsf's relative paths start here.
QUARTUS_DIR = REPO_ROOT / "build" / "quartus"

DIRS = ("in", "out", "inout")
TIMINGS = ("clock", "async_in", "slow_out", "gpio")

GEN_NOTE = "generated from constraints/pins.toml by torqueloop.flow.generate"
TOP_BEGIN = f"// ---- GPIO header map: {GEN_NOTE}; edit there ----"
TOP_END = "// ---- end of the generated GPIO header map ----"
MD_BEGIN = f"<!-- wiring table: {GEN_NOTE}; edit there -->"
MD_END = "<!-- end of the generated wiring table -->"


@dataclass(frozen=True)
class Board:
    name: str
    family: str
    device: str
    top: str
    soc_core: str
    quartus_top: str
    io_standard: str
    clock_period_ns: float
    quartus_version: str = ""      # the Quartus release the generated project is written for


@dataclass(frozen=True)
class Port:
    """One top-level port of the board top (a Terasic board signal name)."""

    name: str
    dir: str
    timing: str
    role: str
    width: int | None = None   # None: scalar

    def bits(self) -> list[str]:
        """Board signal names of every bit: 'CLOCK_50' or 'KEY[0]'..'KEY[3]'."""
        if self.width is None:
            return [self.name]
        return [f"{self.name}[{i}]" for i in range(self.width)]


@dataclass(frozen=True)
class GpioUse:
    """What one GPIO header bit carries."""

    signal: str        # GPIO_0[n]
    header: int        # 40-pin header pin number
    dir: str           # as seen from the FPGA: in | out
    net: str           # board top net (raw pin level)
    device: str
    device_pin: str
    note: str
    pull_up: bool = False

    @property
    def bus(self) -> str:
        return split_bit(self.signal)[0]

    @property
    def index(self) -> int:
        idx = split_bit(self.signal)[1]
        assert idx is not None
        return idx


@dataclass(frozen=True)
class PinTable:
    board: Board
    ports: tuple[Port, ...]
    gpio: tuple[GpioUse, ...]
    firmware: tuple[tuple[str, Path], ...] = ()   # (top parameter, $readmemh image)
    top_parameters: tuple[tuple[str, int], ...] = ()   # numeric parameters of the board top

    def port(self, name: str) -> Port:
        for p in self.ports:
            if p.name == name:
                return p
        raise KeyError(name)

    def port_bits(self) -> list[tuple[Port, str]]:
        return [(p, b) for p in self.ports for b in p.bits()]

    def gpio_by_signal(self) -> dict[str, GpioUse]:
        return {g.signal: g for g in self.gpio}


@dataclass(frozen=True)
class BoardPin:
    signal: str
    pin: str           # FPGA ball, e.g. M9
    io_standard: str


def split_bit(signal: str) -> tuple[str, int | None]:
    """'GPIO_0[12]' -> ('GPIO_0', 12); 'CLOCK_50' -> ('CLOCK_50', None)."""
    m = re.fullmatch(r"([A-Za-z_][A-Za-z0-9_]*)(?:\[(\d+)\])?", signal)
    if not m:
        raise ValueError(f"not a port bit: {signal!r}")
    return m.group(1), (int(m.group(2)) if m.group(2) is not None else None)


def header_pin(gpio_index: int) -> int:
    """Pin of the 40-pin header that carries GPIO_x[gpio_index].

    Standard Terasic layout (DE0-CV user manual, GPIO expansion headers): GPIO[0..9] on pins
    1-10, +5 V on 11, GND on 12, GPIO[10..25] on 13-28, +3.3 V on 29, GND on
    30, GPIO[26..35] on 31-40.
    """
    if not 0 <= gpio_index <= 35:
        raise ValueError(f"GPIO index {gpio_index} outside 0..35")
    if gpio_index <= 9:
        return gpio_index + 1
    if gpio_index <= 25:
        return gpio_index + 3
    return gpio_index + 5


#: Header pins that are power, not GPIO.
HEADER_POWER = {11: "+5 V", 12: "GND", 29: "+3.3 V", 30: "GND"}


# --- loading ---------------------------------------------------------------------------

def load_pin_table(path: Path = PINS_TOML) -> PinTable:
    """Parse constraints/pins.toml (structure only; :func:`validate` checks the content)."""
    with open(path, "rb") as f:
        data = tomllib.load(f)
    b = data["board"]
    board = Board(name=b["name"], family=b["family"], device=b["device"], top=b["top"],
                  soc_core=b["soc_core"], quartus_top=b.get("quartus_top", b["top"]), io_standard=b["io_standard"], clock_period_ns=float(b["clock_period_ns"]),
                  quartus_version=b.get("quartus_version", ""))
    ports = tuple(
        Port(name=p["name"], dir=p["dir"], timing=p["timing"], role=p.get("role", ""),
             width=int(p["width"]) if "width" in p else None)
        for p in data.get("port", [])
    )
    gpio = tuple(
        GpioUse(signal=g["signal"], header=int(g["header"]), dir=g["dir"], net=g["net"],
                device=g["device"], device_pin=g["device_pin"], note=g.get("note", ""),
                pull_up=bool(g.get("pull_up", False)))
        for g in data.get("gpio", [])
    )
    firmware = tuple((name, REPO_ROOT / rel) for name, rel in data.get("firmware", {}).items())
    params = tuple((name, int(v)) for name, v in data.get("top_parameters", {}).items())
    return PinTable(board, ports, gpio, firmware, params)


def load_board_pins(path: Path = BOARD_PINS_CSV) -> dict[str, BoardPin]:
    """Board signal -> location and I/O standard; '#' lines are comments.

    Raises ValueError on a malformed file or a signal listed twice.
    """
    lines = [l for l in path.read_text().splitlines() if l.strip() and not l.lstrip().startswith("#")]
    rows = list(csv.DictReader(io.StringIO("\n".join(lines))))
    if not rows or set(rows[0]) != {"signal", "pin", "io_standard"}:
        raise ValueError(f"{path}: expected the columns signal,pin,io_standard")
    out: dict[str, BoardPin] = {}
    for r in rows:
        sig = r["signal"].strip()
        if sig in out:
            raise ValueError(f"{path}: {sig} listed twice")
        out[sig] = BoardPin(sig, r["pin"].strip(), r["io_standard"].strip())
    return out


# --- validation of the table itself -------------------------------------------------------

def validate(table: PinTable, board_pins: dict[str, BoardPin]) -> list[str]:
    """Every problem of the pin table against the board data (empty = consistent)."""
    problems: list[str] = []
    names = [p.name for p in table.ports]
    for n in {n for n in names if names.count(n) > 1}:
        problems.append(f"port {n} listed twice")
    clocks = [p for p in table.ports if p.timing == "clock"]
    if len(clocks) != 1:
        problems.append(f"expected exactly one clock port, found {[p.name for p in clocks]}")
    used_locations: dict[str, str] = {}
    for p in table.ports:
        if p.dir not in DIRS:
            problems.append(f"port {p.name}: dir {p.dir!r} not in {DIRS}")
        if p.timing not in TIMINGS:
            problems.append(f"port {p.name}: timing {p.timing!r} not in {TIMINGS}")
        if p.timing == "gpio" and p.dir != "inout":
            problems.append(f"port {p.name}: header ports are inout (each bit's use is in [[gpio]])")
        if p.timing in ("clock", "async_in") and p.dir != "in":
            problems.append(f"port {p.name}: timing {p.timing} needs dir in")
        if p.timing == "slow_out" and p.dir != "out":
            problems.append(f"port {p.name}: timing slow_out needs dir out")
        for bit in p.bits():
            bp = board_pins.get(bit)
            if bp is None:
                problems.append(f"port bit {bit} is not a DE0-CV board signal")
                continue
            if bp.io_standard != table.board.io_standard:
                problems.append(f"{bit}: board I/O standard {bp.io_standard!r} != {table.board.io_standard!r}")
            if bp.pin in used_locations:
                problems.append(f"location {bp.pin} used twice: {used_locations[bp.pin]} and {bit}")
            used_locations[bp.pin] = bit
    seen_sig: dict[str, GpioUse] = {}
    seen_net: dict[str, GpioUse] = {}
    for g in table.gpio:
        try:
            bus, idx = split_bit(g.signal)
        except ValueError as e:
            problems.append(str(e))
            continue
        try:
            port = table.port(bus)
        except KeyError:
            problems.append(f"[[gpio]] {g.signal}: no port {bus}")
            continue
        if port.timing != "gpio" or idx is None or port.width is None or not 0 <= idx < port.width:
            problems.append(f"[[gpio]] {g.signal}: not a bit of a header port")
            continue
        if g.signal in seen_sig:
            problems.append(f"[[gpio]] {g.signal} assigned twice ({seen_sig[g.signal].net}, {g.net})")
        seen_sig[g.signal] = g
        if g.net in seen_net:
            problems.append(f"[[gpio]] net {g.net} on two pins ({seen_net[g.net].signal}, {g.signal})")
        seen_net[g.net] = g
        if g.dir not in ("in", "out"):
            problems.append(f"[[gpio]] {g.signal}: dir {g.dir!r} must be in or out")
        if g.header != header_pin(idx):
            problems.append(f"[[gpio]] {g.signal}: header pin {g.header}, but GPIO[{idx}] is on pin {header_pin(idx)}")
        if g.pull_up and g.dir != "in":
            problems.append(f"[[gpio]] {g.signal}: pull_up only makes sense on an input")
        if not re.fullmatch(r"[a-z][a-z0-9_]*(\[\d+\])?", g.net):
            problems.append(f"[[gpio]] {g.signal}: net {g.net!r} is not a lower_snake Verilog name")
    return problems


def compare_board_tables(ours: dict[str, BoardPin], shared: dict[str, BoardPin]) -> list[str]:
    """Differences between the repo's board pin copy and an outside reference table."""
    problems = []
    for sig in sorted(set(ours) | set(shared)):
        a, b = ours.get(sig), shared.get(sig)
        if a is None:
            problems.append(f"{sig}: in the shared board table, missing from {BOARD_PINS_CSV.name}")
        elif b is None:
            problems.append(f"{sig}: in {BOARD_PINS_CSV.name}, not in the shared board table")
        elif (a.pin, a.io_standard) != (b.pin, b.io_standard):
            problems.append(f"{sig}: ours {a.pin} {a.io_standard}, shared {b.pin} {b.io_standard}")
    return problems


# --- generators ------------------------------------------------------------------------------

def _qsf_quote(value: str) -> str:
    return f'"{value}"' if re.search(r"[\s\[\]]", value) else value


def qsf_relpath(path: Path, project_dir: Path = QUARTUS_DIR) -> str:
    """A source path as the .qsf names it: relative to the Quartus project folder, '/' separated."""
    return Path(os.path.relpath(path, project_dir)).as_posix()


def gen_qsf(table: PinTable, board_pins: dict[str, BoardPin], verilog: list[Path],
            sdc: Path = SDC, project_dir: Path = QUARTUS_DIR,
            extra_files: list[tuple[str, Path]] = ()) -> str:
    """The Quartus settings: device, top, sources, every pin's location and I/O standard.

    ``verilog`` is the Quartus top's source list from rtl/manifest.toml (its
    dependency order; headers are not compiled as files but found through
    SEARCH_PATH by the files that include them); ``extra_files`` are
    (assignment name, path) pairs such as ("HEX_FILE", firmware image).
    """
    b = table.board
    out = [
        f"# Quartus settings of the torqueloop board top: {GEN_NOTE}",
        "# and rtl/manifest.toml.  Do not edit: change the sources and run",
        "#   .venv/bin/python -m torqueloop.flow.generate",
        f"# Paths are relative to the Quartus project folder {qsf_relpath(project_dir, REPO_ROOT)}/",
        "# (constraints/create_project.tcl and python -m torqueloop.flow.quartus create it there).",
        "",
        f"set_global_assignment -name FAMILY {_qsf_quote(b.family)}",
        f"set_global_assignment -name DEVICE {b.device}",
        f"set_global_assignment -name TOP_LEVEL_ENTITY {b.quartus_top}",
        "set_global_assignment -name PROJECT_OUTPUT_DIRECTORY output_files",
        *([f"# Written for Quartus Prime {b.quartus_version}; a later release offers to upgrade the project.",
           f"set_global_assignment -name ORIGINAL_QUARTUS_VERSION {b.quartus_version.split()[0]}",
           f"set_global_assignment -name LAST_QUARTUS_VERSION {_qsf_quote(b.quartus_version)}"]
          if b.quartus_version else []),
        "# RESET_N (P22) is the DEV_CLRN-capable pin: keep it an ordinary input.",
        "set_global_assignment -name ENABLE_DEVICE_WIDE_RESET OFF",
        "# Pins the design does not use stay inputs, so nothing on the headers is driven by accident.",
        'set_global_assignment -name RESERVE_ALL_UNUSED_PINS_WEAK_PULLUP "AS INPUT TRI-STATED"',
        "",
        "# Sources (rtl/manifest.toml, core " + b.quartus_top + ")",
    ]
    for p in verilog:
        if p.suffix != ".vh":
            out.append(f"set_global_assignment -name VERILOG_FILE {qsf_relpath(p, project_dir)}")
    # Headers are not compiled on their own: each file that uses their
    # `define names includes them, found in these folders.
    for d in dict.fromkeys(p.parent for p in verilog if p.suffix == ".vh"):
        out.append(f"set_global_assignment -name SEARCH_PATH {qsf_relpath(d, project_dir)}")
    for name, p in extra_files:
        out.append(f"set_global_assignment -name {name} {qsf_relpath(p, project_dir)}")
    out.append(f"set_global_assignment -name SDC_FILE {qsf_relpath(sdc, project_dir)}")
    gpio = table.gpio_by_signal()
    for p in table.ports:
        out += ["", f"# {p.name}: {p.role}"]
        for bit in p.bits():
            if p.timing == "gpio" and bit not in gpio:
                use = "spare, tri-stated"
            elif p.timing == "gpio":
                g = gpio[bit]
                use = f"header pin {g.header}: {g.device} {g.device_pin} ({g.net})"
            else:
                use = ""
            # A comment line of its own: Quartus reads the .qsf as Tcl, where '#' only
            # starts a comment at the beginning of a command.
            if use:
                out.append(f"# {bit}: {use}")
            out.append(f"set_location_assignment PIN_{board_pins[bit].pin} -to {bit}")
            out.append(f"set_instance_assignment -name IO_STANDARD {_qsf_quote(board_pins[bit].io_standard)} -to {bit}")
            if bit in gpio and gpio[bit].pull_up:
                out.append(f"set_instance_assignment -name WEAK_PULL_UP_RESISTOR ON -to {bit}")
    return "\n".join(out) + "\n"


def _ports_list(bits: list[str]) -> str:
    return "[get_ports {" + " ".join(bits) + "}]"


def gen_sdc(table: PinTable) -> str:
    """Timing constraints: the 50 MHz clock, derived uncertainty, false paths
    for the board I/O that the RTL synchronises (inputs) or that only slow
    devices read (outputs from registers)."""
    clk = next(p for p in table.ports if p.timing == "clock")
    out = [
        f"# Timing constraints of the torqueloop board top: {GEN_NOTE}.",
        "# Do not edit: change the pin table and run .venv/bin/python -m torqueloop.flow.generate",
        "",
        f"# {clk.name}: {clk.role}",
        f"create_clock -name {clk.name} -period {table.board.clock_period_ns:.3f} {_ports_list([clk.name])}",
        "derive_pll_clocks",
        "derive_clock_uncertainty",
        "",
        "# Asynchronous inputs: each goes through a synchroniser (sync_2ff, or reset_sync for",
        "# RESET_N) before any logic reads it, so no timing relation to CLOCK_50 exists.",
    ]
    ins = [b for p in table.ports if p.timing == "async_in" for b in p.bits()]
    ins += [g.signal for g in table.gpio if g.dir == "in"]
    outs = [b for p in table.ports if p.timing == "slow_out" for b in p.bits()]
    outs += [g.signal for g in table.gpio if g.dir == "out"]
    for bits in _chunks(ins, 8):
        out.append(f"set_false_path -from {_ports_list(bits)}")
    out += [
        "",
        "# Outputs from registers to LEDs, displays, H-bridge inputs (PWM up to 25 kHz, 20 ns",
        "# resolution) and the 3.3 V UART: a few ns of pin delay change nothing for them.",
    ]
    for bits in _chunks(outs, 8):
        out.append(f"set_false_path -to {_ports_list(bits)}")
    return "\n".join(out) + "\n"


def _chunks(items: list[str], n: int) -> list[list[str]]:
    return [items[i:i + n] for i in range(0, len(items), n)]


def gen_top_gpio_block(table: PinTable, indent: str = "    ") -> str:
    """The board top's GPIO header map: one assign per used header bit, runs
    of spare bits tri-stated together."""
    gpio = table.gpio_by_signal()

    def line(lhs: str, rhs: str, comment: str) -> str:
        return f"{indent}assign {lhs:<19} = {rhs + ';':<20} // {comment}"

    lines = [indent + TOP_BEGIN]
    for p in table.ports:
        if p.timing != "gpio" or p.width is None:
            continue
        spare: list[int] = []

        def flush() -> None:
            if not spare:
                return
            lo, hi = spare[0], spare[-1]
            pins = (f"pin {header_pin(lo)}" if lo == hi
                    else f"pins {header_pin(lo)}-{header_pin(hi)}")
            if lo == hi:
                lines.append(line(f"{p.name}[{lo}]", "1'bz", f"{pins}: spare, tri-stated"))
            else:
                lines.append(line(f"{p.name}[{hi}:{lo}]", f"{{{hi - lo + 1}{{1'bz}}}}", f"{pins}: spare, tri-stated"))
            spare.clear()

        for idx in range(p.width):
            bit = f"{p.name}[{idx}]"
            g = gpio.get(bit)
            # A spare run breaks at the power pins (after GPIO[9] and GPIO[25]).
            if g is None and spare and header_pin(idx) != header_pin(spare[-1]) + 1:
                flush()
            if g is None:
                spare.append(idx)
                continue
            flush()
            where = f"pin {header_pin(idx)}: {g.device} {g.device_pin}"
            if g.dir == "out":
                lines.append(line(bit, g.net, where))
            else:
                lines.append(line(bit, "1'bz", f"pin {header_pin(idx)}: input"))
                lines.append(line(g.net, bit, where))
        flush()
    lines.append(indent + TOP_END)
    return "\n".join(lines) + "\n"


def cable_nets(table: PinTable) -> dict[str, tuple[str, int | None]]:
    """The top's header nets (``ibt2_rpwm_pin`` ...): name -> (dir as seen
    from the FPGA, width or None)."""
    nets: dict[str, tuple[str, int | None]] = {}
    for g in table.gpio:
        name, idx = split_bit(g.net)
        old = nets.get(name, (g.dir, None))[1]
        nets[name] = (g.dir, None if idx is None else max(old or 0, idx + 1))
    return nets


def gen_cable_module(table: PinTable) -> str:
    """The cable harness of the test wrappers around the board top, as a
    module: a port per header net of the top, named as the top's own net
    (``ibt2_rpwm_pin`` ...), read from the header where the FPGA drives it
    and driving the header where the FPGA reads it.  Spare header bits stay
    undriven, so a four-state simulator sees whether the top floats them."""
    ports: list = ["    inout  wire [35:0] GPIO_0,", "    inout  wire [35:0] GPIO_1,"]
    for name, (d, width) in cable_nets(table).items():
        rng = f"[{width - 1}:0]" if width else ""
        where = "FPGA drives it" if d == "out" else "FPGA reads it"
        ports.append((f"    {'output' if d == 'out' else 'input '} wire {rng:<6} {name},", where))
    code = [c for c, _ in ports[2:]]
    code[-1] = code[-1].rstrip(",")
    width = max(map(len, code)) + 1
    ports = ports[:2] + [f"{c:<{width}}// {w}" for c, (_, w) in zip(code, ports[2:])]
    lines = [f"// de0_cv_cable: the cable harness of docs/hardware.md in Verilog, for the board's test",
             f"// wrappers; {GEN_NOTE}; edit there.",
             "// Each header signal meets a port named as the board top's own net.",
             "`default_nettype none", "", "module de0_cv_cable (", *ports, ");"]
    for g in sorted(table.gpio, key=lambda g: (g.bus, g.index)):
        lhs, rhs = (g.net, g.signal) if g.dir == "out" else (g.signal, g.net)
        lines.append(f"    assign {lhs:<19} = {rhs + ';':<20} // pin {g.header}: {g.device} {g.device_pin}")
    lines += ["endmodule", "", "`default_nettype wire", ""]
    return "\n".join(lines)


def quartus_top_v(table: PinTable) -> Path:
    """The generated Quartus top-level file, beside the board top."""
    return TOP_V.with_name(f"{table.board.quartus_top}.v")


def gen_quartus_top(table: PinTable, project_dir: Path = QUARTUS_DIR) -> str:
    """The Quartus top-level entity: the board top with the [firmware] memory
    images as string parameters written in Verilog, relative to the project
    folder (where Quartus resolves $readmemh names), and the numeric
    [top_parameters].  Same ports as the board
    top, one per pin-table port."""
    b = table.board
    items = []
    for p in table.ports:
        d = {"in": "input", "out": "output", "inout": "inout"}[p.dir]
        rng = f"[{p.width - 1}:0] " if p.width else ""
        items.append(f"{d} wire {rng}{p.name}")
    # Four to a line: the ports are the pin table's, stated in full in the board top.
    decl = ["    " + ", ".join(items[i:i + 4]) for i in range(0, len(items), 4)]
    params = ", ".join([*(f'.{name}("{qsf_relpath(image, project_dir)}")' for name, image in table.firmware),
                        *(f".{name}({value})" for name, value in table.top_parameters)])
    conns = ", ".join(f".{p.name}({p.name})" for p in table.ports)
    return "\n".join([
        f"// {b.quartus_top}: the Quartus top-level entity of the {b.name} project, {GEN_NOTE};",
        "// edit there.  It is the board top, rtl/board/" + TOP_V.name + ", with the boot memory",
        "// images as string parameters in Verilog (paths from the Quartus project folder,",
        "// where $readmemh looks), since the .qsf's set_parameter is documented only for numbers,",
        "// and the pin table's [top_parameters] beside them.",
        "`default_nettype none",
        "",
        f"module {b.quartus_top} (",
        ",\n".join(decl),
        ");",
        "",
        f"    {b.top} #({params}) u_top (" if params else f"    {b.top} u_top (",
        f"        {conns}",
        "    );",
        "",
        "endmodule",
        "",
        "`default_nettype wire",
        "",
    ])


def gen_wiring_md(table: PinTable, board_pins: dict[str, BoardPin]) -> str:
    """Markdown wiring table of docs/hardware.md, one row per used header pin."""
    rows = [
        MD_BEGIN,
        "",
        "| header | pin | FPGA ball | signal | dir | goes to | device pin | top net | note |",
        "|---|---:|---|---|---|---|---|---|---|",
    ]
    for g in sorted(table.gpio, key=lambda g: (g.bus, g.header)):
        pull = " (FPGA weak pull-up on)" if g.pull_up else ""
        arrow = "FPGA &rarr;" if g.dir == "out" else "&rarr; FPGA"
        rows.append(f"| {g.bus} | {g.header} | {board_pins[g.signal].pin} | `{g.signal}` | {arrow} "
                    f"| {g.device} | {g.device_pin} | `{g.net}` | {g.note}{pull} |")
    rows += ["", MD_END]
    return "\n".join(rows) + "\n"


def replace_between(text: str, begin: str, end: str, block: str) -> str:
    """Replace the lines from ``begin`` to ``end`` (inclusive, matched as line
    contents) with ``block``; raise if the markers are missing."""
    lines = text.splitlines(keepends=True)
    starts = [i for i, l in enumerate(lines) if l.strip() == begin.strip()]
    ends = [i for i, l in enumerate(lines) if l.strip() == end.strip()]
    if len(starts) != 1 or len(ends) != 1 or ends[0] < starts[0]:
        raise ValueError(f"expected one '{begin.strip()}' ... '{end.strip()}' block")
    return "".join(lines[:starts[0]]) + block + "".join(lines[ends[0] + 1:])


def extract_between(text: str, begin: str, end: str) -> str | None:
    lines = text.splitlines(keepends=True)
    starts = [i for i, l in enumerate(lines) if l.strip() == begin.strip()]
    ends = [i for i, l in enumerate(lines) if l.strip() == end.strip()]
    if len(starts) != 1 or len(ends) != 1 or ends[0] < starts[0]:
        return None
    return "".join(lines[starts[0]:ends[0] + 1])


# --- reading the products back (independently of the generators) ------------------------------

@dataclass
class QsfSettings:
    globals: dict[str, list[str]]                  # name -> values, in order
    locations: dict[str, list[str]]                # port bit -> [PIN_xx, ...]
    instance: dict[tuple[str, str], list[str]]     # (name, target) -> values
    parameters: dict[str, str]                     # top parameter -> value


def parse_qsf(text: str) -> QsfSettings:
    """Read the assignments of a .qsf (Tcl syntax, one command per line)."""
    s = QsfSettings({}, {}, {}, {})
    for n, line in enumerate(text.splitlines(), 1):
        line = line.strip()
        if not line or line.startswith("#"):
            continue
        words = shlex.split(line)
        cmd, args = words[0], words[1:]
        opts: dict[str, str] = {}
        rest: list[str] = []
        i = 0
        while i < len(args):
            if args[i] in ("-name", "-to", "-from", "-section_id", "-entity"):
                opts[args[i]] = args[i + 1]
                i += 2
            else:
                rest.append(args[i])
                i += 1
        if cmd == "set_global_assignment":
            s.globals.setdefault(opts["-name"], []).append(" ".join(rest))
        elif cmd == "set_location_assignment":
            s.locations.setdefault(opts["-to"], []).append(" ".join(rest))
        elif cmd == "set_instance_assignment":
            s.instance.setdefault((opts["-name"], opts["-to"]), []).append(" ".join(rest))
        elif cmd == "set_parameter":
            s.parameters[opts["-name"]] = " ".join(rest)
        else:
            raise ValueError(f"line {n}: unexpected command {cmd}")
    return s


def sdc_port_names(text: str) -> list[str]:
    """Every name inside [get_ports {...}] / [get_ports name] of an .sdc."""
    names: list[str] = []
    for m in re.finditer(r"\[get_ports\s+(\{[^}]*\}|\S+?)\]", text):
        body = m.group(1).strip("{}")
        names += body.split()
    return names


def top_ports(verilog: Path, top: str, headers: list[Path] = ()) -> dict[str, tuple[str, int | None]]:
    """Ports of the board top as Yosys reads them: name -> (dir, width or None).

    Only the top file is read, with the folders of ``headers`` (the `define
    files it includes) as include paths; submodules stay unresolved, so this
    works before the rest of the design elaborates.  A 1-bit port declared
    without a range is reported as scalar.
    """
    incdirs = " ".join(f"-I{d}" for d in dict.fromkeys(h.parent for h in headers))
    with tempfile.TemporaryDirectory() as tmp:
        js = Path(tmp) / "top.json"
        proc = subprocess.run(
            ["yosys", "-q", "-p", f"read_verilog {incdirs} {verilog}; write_json {js}"],
            capture_output=True, text=True, cwd=REPO_ROOT)
        if proc.returncode != 0:
            raise RuntimeError(f"yosys could not read {verilog}:\n{proc.stderr or proc.stdout}")
        mod = json.loads(js.read_text())["modules"][top]
    text = verilog.read_text()
    out: dict[str, tuple[str, int | None]] = {}
    for name, p in mod["ports"].items():
        d = {"input": "in", "output": "out", "inout": "inout"}[p["direction"]]
        width = len(p["bits"])
        ranged = re.search(rf"\[[^\]]+\]\s*{re.escape(name)}\b", text) is not None
        out[name] = (d, width if (width > 1 or ranged) else None)
    return out


def elaborate(files: list[Path], top: str, cwd: Path = REPO_ROOT,
              include_dirs: list[Path] = (), params: dict[str, int] | None = None) -> tuple[bool, str]:
    """Yosys hierarchy -check over exactly these files (headers found through
    ``include_dirs``, as Quartus finds them through SEARCH_PATH), the top's
    ``params`` set: every module resolved."""
    names = " ".join(str(f) for f in files)
    incdirs = " ".join(f"-I{d}" for d in include_dirs)
    chparams = "".join(f" -chparam {k} {int(v)}" for k, v in (params or {}).items())
    proc = subprocess.run(["yosys", "-q", "-p",
                           f"read_verilog -defer {incdirs} {names}; hierarchy -check -top {top}{chparams}"],
                          capture_output=True, text=True, cwd=cwd)
    return proc.returncode == 0, (proc.stdout + proc.stderr).strip()
