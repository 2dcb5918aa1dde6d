# SPDX-License-Identifier: MIT
"""The strict second front end of make lint (slang, torqueloop/flow/strict.py):
every core passes, and what it is there for - a name used before its
declaration, a macro borrowed from another file, an unreviewed warning - is
caught when planted once."""

from __future__ import annotations

from pathlib import Path

from torqueloop.flow import strict
from torqueloop.flow.manifest import REPO_ROOT, Core, core


def test_every_core_passes_the_strict_front_end():
    bad = [r for r in strict.check_all() if not r.ok]
    assert not bad, "\n".join(line for r in bad for line in r.errors + r.warnings)


def _with(c: Core, replaced: Path, planted: Path) -> Core:
    return Core(c.name, c.top, tuple(planted if p == replaced else p for p in c.verilog), ())


def test_a_name_used_before_its_declaration_is_an_error(tmp_path):
    c = core("cpu")
    cpu_v = REPO_ROOT / "rtl" / "cpu" / "tl_cpu.v"
    text = cpu_v.read_text()
    assert "    wire        md_fin;\n" in text and "    assign md_fin = md_done || md_done_q;\n" in text
    planted = tmp_path / "tl_cpu.v"
    planted.write_text(text.replace("    wire        md_fin;\n", "")
                       .replace("    assign md_fin = md_done || md_done_q;\n", "    wire md_fin = md_done || md_done_q;\n"))
    r = strict.check_core(_with(c, cpu_v, planted))
    assert any("md_fin" in e and "before its declaration" in e for e in r.errors), r.errors


def test_a_macro_from_another_file_is_not_enough(tmp_path):
    """Each file is its own compilation unit: the header listed first (as the
    manifest used to rely on) does not stand in for a file's own include."""
    c = core("soc_timer")
    timer_v = REPO_ROOT / "rtl" / "soc" / "tl_soc_timer.v"
    planted = tmp_path / timer_v.name
    # both includes go: tl_soc_page.vh includes regmap.vh itself
    planted.write_text(timer_v.read_text().replace('`include "regmap.vh"\n', "")
                       .replace('`include "tl_soc_page.vh"\n', ""))
    header_first = Core(c.name, c.top, (REPO_ROOT / "rtl/soc/regmap.vh", planted), ())
    # regmap.vh is a header: compiled only through includes, so list it as a source explicitly
    r = strict.check_core(header_first, extra_args=[str(REPO_ROOT / "rtl/soc/regmap.vh")])
    assert any("TL_" in e for e in r.errors), r.errors


def test_an_unreviewed_warning_fails(tmp_path):
    f = tmp_path / "trunc.v"
    f.write_text("`default_nettype none\nmodule trunc(output wire [3:0] y);\n    assign y = 8'hA5;\nendmodule\n")
    r = strict.check_core(Core("trunc", "trunc", (f,), ()))
    assert not r.errors and r.warnings and not r.ok, (r.errors, r.warnings)
