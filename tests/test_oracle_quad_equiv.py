# SPDX-License-Identifier: MIT
"""The VHDL/Verilog equivalence proof of quad_decoder rejects broken twins."""

import pytest

from torqueloop.flow import eda
from torqueloop.flow.manifest import core


@pytest.mark.parametrize("good,bad", [
    ("up      <= prev(1) xor filt(0);", "up      <= prev(0) xor filt(1);"),
    ("elsif ('0' & c) + 1 >= n_eff then", "elsif ('0' & c) + 1 > n_eff then"),
])
def test_equivalence_catches_a_broken_quad_decoder_twin(tmp_path, good, bad):
    c = core("quad_decoder")
    src = c.vhdl[-1].read_text()
    assert good in src
    broken = tmp_path / "quad_decoder.vhd"
    broken.write_text(src.replace(good, bad))
    assert eda.equivalence(c, work=tmp_path / "good").ok
    r = eda.equivalence(c, vhdl_override=[*c.vhdl[:-1], broken], seq=1, work=tmp_path / "bad")
    assert not r.ok and "ghdl synth failed" not in r.detail, r.detail
