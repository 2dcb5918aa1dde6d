# SPDX-License-Identifier: MIT
"""DE0-CV constraints: the repo's files are consistent, and the checks catch
the mistakes they exist for (a pin twice, a wrong ball, a missing I/O
standard, an .sdc naming a port that does not exist, a SoC file left out)."""

from __future__ import annotations

import dataclasses
import re
from pathlib import Path

import pytest

from torqueloop.flow import board_files as board, constraints_check as board_check, quartus
from torqueloop.flow.manifest import REPO_ROOT, Core, load_manifest


@pytest.fixture(scope="module")
def table() -> board.PinTable:
    return board.load_pin_table()


@pytest.fixture(scope="module")
def pins() -> dict[str, board.BoardPin]:
    return board.load_board_pins()


FAKE_SOURCES = [REPO_ROOT / "rtl/common/tl_reset_sync.v", REPO_ROOT / "rtl/board/de0_cv_top.v"]


# --- the header layout and the board data ----------------------------------------------------

def test_header_pins_follow_the_terasic_layout():
    assert [board.header_pin(i) for i in (0, 9, 10, 25, 26, 35)] == [1, 10, 13, 28, 31, 40]
    gpio_pins = {board.header_pin(i) for i in range(36)}
    assert len(gpio_pins) == 36
    assert gpio_pins | set(board.HEADER_POWER) == set(range(1, 41))
    assert not gpio_pins & set(board.HEADER_POWER)


def test_board_copy_equals_shared_table():
    c = board_check.check_board_copy()
    if c.skipped:
        pytest.skip(c.detail)
    assert c.ok, c.detail


def test_board_table_compare_catches_a_changed_ball(pins):
    changed = dict(pins)
    changed["LEDR[3]"] = dataclasses.replace(pins["LEDR[3]"], pin="Y4")
    del changed["KEY[1]"]
    problems = board.compare_board_tables(changed, pins)
    assert any("LEDR[3]" in p and "Y4" in p for p in problems)
    assert any("KEY[1]" in p for p in problems)


def test_board_pin_file_rejects_a_signal_listed_twice(tmp_path):
    f = tmp_path / "pins.csv"
    f.write_text("# comment\nsignal,pin,io_standard\nKEY[0],U7,3.3-V LVTTL\nKEY[0],W9,3.3-V LVTTL\n")
    with pytest.raises(ValueError, match="twice"):
        board.load_board_pins(f)


# --- the pin table -------------------------------------------------------------------------

def test_pin_table_is_consistent(table, pins):
    assert board.validate(table, pins) == []


def test_every_ibt2_encoder_and_uart_signal_has_a_pin(table):
    nets = {g.net for g in table.gpio}
    for axis in (0, 1):
        for n in ("ibt2_rpwm_pin", "ibt2_lpwm_pin", "ibt2_r_en_pin", "ibt2_l_en_pin",
                  "ibt2_fault_pin", "enc_a_pin", "enc_b_pin", "enc_z_pin"):
            assert f"{n}[{axis}]" in nets
    assert {"uart_rx_pin", "uart_tx_pin", "uart_cts_n_pin", "uart_rts_n_pin"} <= nets
    # An input a user may leave unconnected must read its idle level, not float.
    assert all(g.pull_up for g in table.gpio if g.dir == "in")


def _with_gpio(table: board.PinTable, gpio: list[board.GpioUse]) -> board.PinTable:
    return dataclasses.replace(table, gpio=tuple(gpio))


def test_validate_catches_pin_table_mistakes(table, pins):
    g = list(table.gpio)
    # the same header bit twice
    twice = _with_gpio(table, g + [dataclasses.replace(g[0], net="spare_net")])
    assert any("assigned twice" in p for p in board.validate(twice, pins))
    # one net on two pins
    dup_net = _with_gpio(table, g + [dataclasses.replace(g[0], signal="GPIO_1[30]", header=35)])
    assert any("on two pins" in p for p in board.validate(dup_net, pins))
    # wrong header pin number (pin 11 is +5 V)
    bad_hdr = _with_gpio(table, [dataclasses.replace(g[0], signal="GPIO_0[10]", header=11)] + g[1:])
    assert any("header pin 11" in p for p in board.validate(bad_hdr, pins))
    # a port wider than the board signal
    wide = dataclasses.replace(table, ports=tuple(
        dataclasses.replace(p, width=11) if p.name == "SW" else p for p in table.ports))
    assert any("SW[10]" in p for p in board.validate(wide, pins))
    # a board pin with another I/O standard than the table's
    odd = dict(pins)
    odd["KEY[2]"] = dataclasses.replace(pins["KEY[2]"], io_standard="2.5 V")
    assert any("KEY[2]" in p for p in board.validate(table, odd))
    # two ports on the same ball
    same_ball = dict(pins)
    same_ball["LEDR[0]"] = dataclasses.replace(pins["LEDR[0]"], pin=pins["LEDR[1]"].pin)
    assert any("used twice" in p for p in board.validate(table, same_ball))


# --- generated products, read back independently -----------------------------------------------

def test_qsf_pins_check_passes_on_generated_qsf(table, pins):
    qsf = board.gen_qsf(table, pins, FAKE_SOURCES)
    c = board_check.check_qsf_pins(table, pins, qsf)
    assert c.ok, c.detail
    s = board.parse_qsf(qsf)
    assert s.locations["CLOCK_50"] == ["PIN_M9"] and s.locations["RESET_N"] == ["PIN_P22"]
    assert len(s.locations) == sum(len(p.bits()) for p in table.ports) == 140


@pytest.mark.parametrize("mutation, expect", [
    (lambda q: q.replace("PIN_N16 -to GPIO_0[0]", "PIN_B16 -to GPIO_0[0]"), "GPIO_0[0]: location PIN_B16"),
    (lambda q: q.replace("PIN_N16 -to GPIO_0[0]", "PIN_B16 -to GPIO_0[0]"), "used twice"),
    (lambda q: re.sub(r'set_instance_assignment -name IO_STANDARD "3.3-V LVTTL" -to SW\[3\]\n', "", q),
     "SW[3]: IO_STANDARD []"),
    (lambda q: q.replace('IO_STANDARD "3.3-V LVTTL" -to HEX2[1]', 'IO_STANDARD "2.5 V" -to HEX2[1]'), "HEX2[1]"),
    (lambda q: q + "set_location_assignment PIN_H13 -to CLOCK2_50\n", "CLOCK2_50"),
    (lambda q: re.sub(r"set_location_assignment PIN_\w+ -to KEY\[1\]\n", "", q), "KEY[1]: 0 location"),
    (lambda q: q.replace("WEAK_PULL_UP_RESISTOR ON -to GPIO_0[6]", "WEAK_PULL_UP_RESISTOR OFF -to GPIO_0[6]"),
     "weak pull-ups"),
    (lambda q: q.replace("ENABLE_DEVICE_WIDE_RESET OFF", "ENABLE_DEVICE_WIDE_RESET ON"), "ENABLE_DEVICE_WIDE_RESET"),
    (lambda q: q.replace("DEVICE 5CEBA4F23C7", "DEVICE 5CEBA2F23C7"), "DEVICE"),
])
def test_qsf_pins_check_catches(table, pins, mutation, expect):
    qsf = board.gen_qsf(table, pins, FAKE_SOURCES)
    bad = mutation(qsf)
    assert bad != qsf
    c = board_check.check_qsf_pins(table, pins, bad)
    assert not c.ok and expect in c.detail, c.detail


def test_firmware_images_become_string_parameters_in_the_quartus_top(table, pins):
    """[firmware] entries reach the board top as Verilog string parameters of
    the generated Quartus top, relative to the project folder, and the .qsf
    names that top and carries no set_parameter (Intel documents it only for
    numbers)."""
    with_fw = dataclasses.replace(table, firmware=(("ROM_INIT", REPO_ROOT / "build" / "fw" / "boot.hex"),))
    s = board.parse_qsf(board.gen_qsf(with_fw, pins, FAKE_SOURCES))
    assert s.parameters == {}
    assert s.globals["TOP_LEVEL_ENTITY"] == [table.board.quartus_top]
    text = board.gen_quartus_top(with_fw)
    params = "".join(f", .{n}({v})" for n, v in table.top_parameters)
    assert f'{table.board.top} #(.ROM_INIT("../fw/boot.hex"){params}) u_top' in text
    for p in table.ports:
        assert re.search(rf"\b{p.name}\b", text), p.name


def test_bridge_fault_inputs_are_declared_wired_by_default(table):
    """An open bridge-fault line reads as a fault (weak pull-up, active-high
    fault) on every axis the build declares wired, and the default build
    declares both (docs/hardware.md, IS pins)."""
    assert dict(table.top_parameters)["BRIDGE_FAULT_WIRED"] == 0b11
    faults = [g for g in table.gpio if g.net.startswith("ibt2_fault_pin[")]
    assert len(faults) == 2 and all(g.pull_up and g.dir == "in" for g in faults)
    assert ".BRIDGE_FAULT_WIRED(3)" in board.gen_quartus_top(table)


def test_sdc_check(table):
    sdc = board.gen_sdc(table)
    bits = {b for _, b in table.port_bits()}
    assert board_check.check_sdc(table, sdc, bits).ok
    # every synchronised input and every slow output is cut, the clock is not
    named = set(board.sdc_port_names(sdc))
    assert {"RESET_N", "KEY[0]", "SW[0]", "GPIO_0[6]", "GPIO_0[10]", "LEDR[9]", "GPIO_0[0]"} <= named
    assert board_check.check_sdc(table, sdc + "set_false_path -to [get_ports {LEDR[*]}]\n", bits).ok
    c = board_check.check_sdc(table, sdc + "set_false_path -from [get_ports {ENC_A}]\n", bits)
    assert not c.ok and "ENC_A" in c.detail
    c = board_check.check_sdc(table, sdc + "set_false_path -from [get_ports {CLOCK_50}]\n", bits)
    assert not c.ok and "clock port" in c.detail
    c = board_check.check_sdc(table, sdc.replace("-period 20.000", "-period 10.000"), bits)
    assert not c.ok and "create_clock" in c.detail


def test_gpio_block_drives_outputs_reads_inputs_and_tristates_the_rest(table):
    block = board.gen_top_gpio_block(table)
    driven: dict[str, str] = {}
    read: dict[str, str] = {}
    for lhs, rhs in re.findall(r"assign\s+(\S+)\s*=\s*([^;]+);", block):
        m = re.fullmatch(r"(GPIO_[01])\[(\d+)(?::(\d+))?\]", lhs)
        if m:
            hi = int(m.group(2))
            lo = int(m.group(3)) if m.group(3) else hi
            for i in range(lo, hi + 1):
                bit = f"{m.group(1)}[{i}]"
                assert bit not in driven, f"{bit} assigned twice"
                driven[bit] = rhs.strip()
        else:
            read[lhs] = rhs.strip()
    assert len(driven) == 72
    for g in table.gpio:
        if g.dir == "out":
            assert driven[g.signal] == g.net
        else:
            assert "'bz" in driven[g.signal] and read[g.net] == g.signal
    used = {g.signal for g in table.gpio}
    assert all("'bz" in v for k, v in driven.items() if k not in used)


def test_cable_module_is_the_mirror_of_the_top_block(table):
    """The test wrappers' cable harness (de0_cv_cable): every header bit the
    top drives is read into the port named as the top's net, every bit it
    reads is driven from it, and spare bits are left alone (so the board
    bench can see them float)."""
    text = board.gen_cable_module(table)
    pairs = re.findall(r"assign\s+(\S+)\s*=\s*([^;]+);", text)
    assert len(pairs) == len(table.gpio)
    got = {(lhs, rhs.strip()) for lhs, rhs in pairs}
    for g in table.gpio:
        assert ((g.net, g.signal) if g.dir == "out" else (g.signal, g.net)) in got, g.signal
    for name, (d, _) in board.cable_nets(table).items():
        assert re.search(rf"{'output' if d == 'out' else 'input'}\s+wire\s+(\[\d+:0\])?\s*{name}\b", text), name


def test_generate_check_covers_the_cable_module():
    """The cable harness is a generated product: `python -m
    torqueloop.flow.generate --check` (make lint) lists it, and one that
    differs from the pin table is reported stale."""
    from torqueloop.flow import generate

    prods = generate.products()
    rel = str(board.CABLE_V.relative_to(REPO_ROOT))
    assert rel in prods
    planted = dict(prods)
    planted[rel] = prods[rel].replace("= GPIO_0[6];", "= GPIO_0[5];").replace("GPIO_0[6] ", "GPIO_0[5] ")
    assert planted[rel] != prods[rel]
    assert rel in generate.stale(planted)


# --- the top and the project's sources -------------------------------------------------------------

def test_top_ports_match_the_pin_table(table):
    c = board_check.check_top_ports(table)
    assert c.ok, c.detail


def test_top_ports_check_catches_a_port_without_pin(table, tmp_path):
    text = board.TOP_V.read_text()
    extra = tmp_path / "de0_cv_top.v"
    extra.write_text(text.replace("    input  wire        RESET_N,\n",
                                  "    input  wire        RESET_N,\n    output wire        BUZZER,\n"))
    c = board_check.check_top_ports(table, extra)
    assert not c.ok and "BUZZER" in c.detail
    narrow = tmp_path / "narrow" / "de0_cv_top.v"
    narrow.parent.mkdir()
    narrow.write_text(text.replace("input  wire [9:0]  SW,", "input  wire [7:0]  SW,"))
    c = board_check.check_top_ports(table, narrow)
    assert not c.ok and "SW" in c.detail


def _core(name: str, files: list[Path]) -> Core:
    return Core(name=name, top=name, verilog=tuple(files), vhdl=())


def _params(table) -> str:
    """The pin table's [top_parameters] declared, as the board top declares them."""
    return "#(" + ", ".join(f"parameter {n} = 0" for n, _ in table.top_parameters) + ")"


def test_sources_check_sees_the_quartus_build_of_the_flash(table, pins, tmp_path):
    """With [top_parameters] (FLASH_ASMI = 1) the top instantiates the Cyclone V's ASMI
    block: the check elaborates that with the primitive's interface from rtl/lint_only/,
    fails without it, and refuses a project that compiles the interface itself."""
    stub = quartus.LINT_ONLY / "cyclonev_asmiblock.v"
    a, top = tmp_path / "soc_a.v", tmp_path / "de0_cv_top.v"
    a.write_text("module soc_a; endmodule\n")
    top.write_text(f"module de0_cv_top {_params(table)}; soc_a ua();\n"
                   "generate if (FLASH_ASMI != 0) begin : g_asmi cyclonev_asmiblock u_asmi (); end endgenerate\n"
                   "endmodule\n")
    soc = _core(table.board.soc_core, [a])
    full = _core(table.board.quartus_top, [a, top, stub])
    c = board_check.check_qsf_sources(table, board.gen_qsf(table, pins, quartus.project_sources([a, top, stub])),
                                      {soc.name: soc, full.name: full})
    assert c.ok, c.detail
    bare = _core(table.board.quartus_top, [a, top])
    c = board_check.check_qsf_sources(table, board.gen_qsf(table, pins, [a, top]), {soc.name: soc, bare.name: bare})
    assert not c.ok and "cyclonev_asmiblock" in c.detail and "FLASH_ASMI" in c.detail, c.detail
    c = board_check.check_qsf_sources(table, board.gen_qsf(table, pins, [a, top, stub]),
                                      {soc.name: soc, full.name: full})
    assert not c.ok and "vendor primitive's interface" in c.detail, c.detail


def test_sources_check_catches_a_missing_soc_file(table, pins, tmp_path):
    a, b, top = (tmp_path / n for n in ("soc_a.v", "soc_b.v", "de0_cv_top.v"))
    a.write_text("module soc_a; endmodule\n")
    b.write_text("module soc_b; endmodule\n")
    top.write_text(f"module de0_cv_top {_params(table)}; soc_a ua(); soc_b ub(); endmodule\n")
    soc = _core(table.board.soc_core, [a, b])
    full = _core(table.board.quartus_top, [a, b, top])
    cores = {soc.name: soc, full.name: full}
    good = board.gen_qsf(table, pins, [a, b, top])
    c = board_check.check_qsf_sources(table, good, cores)
    assert c.ok, c.detail
    # the project left out soc_b.v (and the manifest's top list too)
    short = _core(table.board.quartus_top, [a, top])
    bad = board.gen_qsf(table, pins, [a, top])
    c = board_check.check_qsf_sources(table, bad, {soc.name: soc, short.name: short})
    assert not c.ok and "soc_b.v is not in the Quartus project" in c.detail
    # a qsf that differs from the manifest's list
    c = board_check.check_qsf_sources(table, bad, cores)
    assert not c.ok and "differs from rtl/manifest.toml" in c.detail


def test_sources_check_elaborates(table, pins, tmp_path):
    """The Yosys elaboration finds a module that no listed file defines."""
    a, top = tmp_path / "soc_a.v", tmp_path / "de0_cv_top.v"
    a.write_text("module soc_a; endmodule\n")
    top.write_text(f"module de0_cv_top {_params(table)}; soc_a ua(); soc_missing um(); endmodule\n")
    cores = {table.board.soc_core: _core(table.board.soc_core, [a]),
             table.board.quartus_top: _core(table.board.quartus_top, [a, top])}
    c = board_check.check_qsf_sources(table, board.gen_qsf(table, pins, [a, top]), cores)
    assert not c.ok and "soc_missing" in c.detail


def test_readmemh_image_check(tmp_path):
    good = tmp_path / "ok.hex"
    good.write_text("// boot\n@0\n00000013\ndeadbeef\n")
    assert quartus.check_readmemh(good) == []
    assert quartus.check_readmemh(good, max_words=2) == []
    assert any("do not fit" in p for p in quartus.check_readmemh(good, max_words=1))
    bad = tmp_path / "bad.hex"
    bad.write_text("00000013\n:020000040000FA\n")     # an Intel HEX record is not $readmemh
    assert quartus.check_readmemh(bad)


# --- the repository as committed ------------------------------------------------------------------

def test_repository_constraints_are_consistent():
    """What CI runs (python -m torqueloop.flow constraints): every check on the committed files."""
    cores = load_manifest()
    t = board.load_pin_table()
    if t.board.top not in cores:
        pytest.skip(f"core {t.board.top} not in rtl/manifest.toml yet (waits for rtl/soc/tl_soc.v)")
    failed = [c for c in board_check.run_all() if not c.ok]
    assert not failed, "\n".join(f"{c.name}:\n{c.detail[:3000]}" for c in failed)


def test_create_project_tcl_writes_the_project_and_compiles(tmp_path):
    """constraints/create_project.tcl under tclsh, with the four Quartus
    commands it uses stubbed: it must write build/quartus/de0_cv_top.qpf and
    an exact copy of the committed .qsf, and only with 'compile' open the
    project and run the compile flow."""
    import shutil
    import subprocess

    if shutil.which("tclsh") is None:
        pytest.skip("tclsh not installed")
    (tmp_path / "constraints").mkdir()
    for f in ("create_project.tcl", "de0_cv_top.qsf"):
        shutil.copy(REPO_ROOT / "constraints" / f, tmp_path / "constraints" / f)
    stubs = tmp_path / "stubs.tcl"
    stubs.write_text(
        "proc load_package {args} { puts \"STUB load_package $args\" }\n"
        "proc project_open {args} { puts \"STUB project_open $args\" }\n"
        "proc execute_flow {args} { puts \"STUB execute_flow $args\" }\n"
        "proc project_close {args} { puts \"STUB project_close\" }\n"
        "set argv0 [lindex $argv 0]\nset argv [lrange $argv 1 end]\n"
        "source $argv0\n")
    script = tmp_path / "constraints" / "create_project.tcl"
    only = subprocess.run(["tclsh", str(stubs), str(script)], capture_output=True, text=True, check=True)
    proj = tmp_path / "build" / "quartus"
    assert 'PROJECT_REVISION = "de0_cv_top"' in (proj / "de0_cv_top.qpf").read_text()
    assert (proj / "de0_cv_top.qsf").read_text() == (REPO_ROOT / "constraints" / "de0_cv_top.qsf").read_text()
    assert "STUB" not in only.stdout
    full = subprocess.run(["tclsh", str(stubs), str(script), "compile"], capture_output=True, text=True, check=True)
    assert "STUB project_open -revision de0_cv_top de0_cv_top" in full.stdout
    assert "STUB execute_flow -compile" in full.stdout


# --- make quartus: the timing verdict after a compile ---------------------------------------------

STA_SUMMARY = """------------------------------------------------------------
Timing Analyzer Summary
------------------------------------------------------------

Type  : Slow 1100mV 85C Model Setup 'CLOCK_50'
Slack : {setup}
TNS   : 0.000

Type  : Slow 1100mV 85C Model Hold 'CLOCK_50'
Slack : 0.341
TNS   : 0.000
"""


def test_timing_verdict_reads_the_summary_and_fails_on_negative_slack(tmp_path):
    f = tmp_path / "de0_cv_top.sta.summary"
    f.write_text(STA_SUMMARY.format(setup="3.127"))
    met, lines = quartus.timing_verdict(f)
    assert met and len(lines) == 2 and "+3.127" in lines[0]
    f.write_text(STA_SUMMARY.format(setup="-0.412"))
    met, lines = quartus.timing_verdict(f)
    assert not met and lines[0].startswith("FAIL") and "Setup 'CLOCK_50'" in lines[0]
    assert not quartus.timing_verdict(tmp_path / "missing.summary")[0]
    f.write_text("Timing Analyzer Summary\n")
    assert not quartus.timing_verdict(f)[0]


def test_compile_without_quartus_prints_the_commands(tmp_path, monkeypatch, capsys):
    """make quartus on a machine without Quartus: the exact commands, exit 0."""
    monkeypatch.setattr(quartus.shutil, "which", lambda name: None)
    qpf = REPO_ROOT / "build" / "quartus" / "de0_cv_top.qpf"
    assert quartus.compile_project(qpf) == 0
    out = capsys.readouterr().out
    assert "cd build/quartus && quartus_sh --flow compile de0_cv_top" in out
    assert "sta.summary" in out and "quartus_pgm" in out
