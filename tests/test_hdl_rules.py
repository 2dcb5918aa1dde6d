# SPDX-License-Identifier: MIT
"""The Quartus-safety rules of make lint (torqueloop/flow/hdl_rules.py): the
tree obeys them, and each mistake they exist for, planted once in a copy of
a real file, is caught."""

from __future__ import annotations

from pathlib import Path

import pytest

from torqueloop.flow import hdl_rules
from torqueloop.flow.manifest import REPO_ROOT

SOC = REPO_ROOT / "rtl" / "soc"


def test_the_tree_obeys_the_rules():
    found = hdl_rules.check()
    assert not found, "\n".join(map(str, found))


def _planted(tmp_path: Path, src: Path, old: str, new: str) -> Path:
    text = src.read_text()
    assert old in text, f"{src.name} no longer contains {old!r}"
    out = tmp_path / src.name
    out.write_text(text.replace(old, new, 1))
    return out


def _rules(path: Path, synthesised: bool = True) -> set[str]:
    found = hdl_rules.check([path], [path] if synthesised else [])
    return {f.rule for f in found}


def test_a_register_map_name_without_the_include_is_caught(tmp_path):
    f = _planted(tmp_path, SOC / "tl_soc_timer.v", '`include "regmap.vh"\n', "")
    assert _rules(f, synthesised=False) == {"include"}


def test_the_include_after_the_first_use_is_caught(tmp_path):
    f = _planted(tmp_path, SOC / "tl_soc_timer.v", '`include "regmap.vh"\n', "")
    f.write_text(f.read_text().replace("endmodule", '`include "regmap.vh"\nendmodule'))
    assert _rules(f, synthesised=False) == {"include"}


@pytest.mark.parametrize("old,new,why", [
    # an asynchronous read: Quartus would build the 64 KiB in logic, not M10K
    ("    always @(posedge clk) begin        // port B: the template's port with its write enable tied low\n"
     "        b_rdata <= mem[b_idx];\n    end\n",
     "    always @(*) b_rdata = mem[b_idx];\n", "read outside a clocked block"),
    # a reset on the array: block RAM has none
    ("        if (a_we) begin\n", "        if (a_rst) mem[0] <= 32'd0;\n        if (a_we) begin\n", "reset"),
    # both ports' writes in one block: a priority the block RAM cannot do
    ("            if (a_be[3]) mem[a_idx][31:24] <= a_wdata[31:24];\n",
     "            if (a_be[3]) mem[a_idx][31:24] <= a_wdata[31:24];\n            mem[b_idx] <= a_wdata;\n",
     "2 addresses in one block"),
    # a third port
    ("    always @(posedge clk) begin        // port B",
     "    always @(posedge clk) a_rdata <= mem[b_idx];\n    always @(posedge clk) begin        // port B", "two ports"),
    # no template named
    ("// Intel template:", "// Template:", "names no Intel inference template"),
])
def test_a_memory_that_departs_from_its_template_is_caught(tmp_path, old, new, why):
    f = _planted(tmp_path, SOC / "tl_soc_ram.v", old, new)
    found = hdl_rules.check([f], [f])
    assert found and all(x.rule == "memory" for x in found), found
    assert any(why in x.text for x in found), [str(x) for x in found]


def test_a_system_task_in_synthesised_code_is_caught(tmp_path):
    f = _planted(tmp_path, SOC / "tl_soc_rom.v", "        b_rdata <= mem[b_addr[ADDR_BITS-1:2]];\n",
                 "        b_rdata <= mem[b_addr[ADDR_BITS-1:2]];\n        $display(\"fetch\");\n")
    assert _rules(f) == {"system-function"}


def test_readmemh_outside_an_initial_block_is_caught(tmp_path):
    f = _planted(tmp_path, SOC / "tl_soc_rom.v", "    always @(posedge clk) begin\n",
                 "    always @(posedge clk) begin\n        $readmemh(INIT_FILE, mem);\n")
    assert "system-function" in _rules(f)


def test_comments_and_simulation_branches_do_not_count(tmp_path):
    """A register-map name in a comment needs no include; code under
    `ifdef (a macro Quartus does not define) is not synthesised code."""
    f = tmp_path / "ok.v"
    f.write_text("// uses `TL_CLK_HZ only in this comment\n`default_nettype none\n"
                 "module ok(input wire clk);\n`ifdef SIMULATION\n    initial $display(\"hi\");\n`endif\n"
                 "endmodule\n")
    assert hdl_rules.check([f], [f]) == []


def test_an_include_written_in_a_comment_does_not_count(tmp_path):
    f = _planted(tmp_path, SOC / "tl_soc_timer.v", '`include "regmap.vh"\n', '// `include "regmap.vh"\n')
    assert _rules(f, synthesised=False) == {"include"}
