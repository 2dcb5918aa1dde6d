# SPDX-License-Identifier: MIT
"""The VHDL/Verilog equivalence proofs of the UART cores reject broken twins:
one mutant per file, each checked on its own core, including a FIFO mutant
that only shows once the FIFO is full."""

import pytest

from torqueloop.flow import eda
from torqueloop.flow.manifest import core

MUTANTS = [
    # (core, file name, good text, broken text)
    ("uart_rx", "tl_uart_rx.vhd",
     "bit_val <= (votes(0) and votes(1)) or (votes(0) and rx) or (votes(1) and rx);",
     "bit_val <= votes(1);"),
    ("uart_tx", "tl_uart_tx.vhd", "bits_left <= to_unsigned(10, 4);", "bits_left <= to_unsigned(9, 4);"),
    ("uart", "tl_uart.vhd", "unsigned(rx_level_i) >= RTS_LEVEL", "unsigned(rx_level_i) > RTS_LEVEL"),
    ("sync_fifo", "tl_sync_fifo.vhd",
     "full    <= '1' when level_i = to_unsigned(DEPTH, AW + 1) else '0';",
     "full    <= '1' when level_i = to_unsigned(DEPTH - 1, AW + 1) else '0';"),
]


@pytest.mark.parametrize("core_name,fname,good,bad", MUTANTS, ids=[m[1] for m in MUTANTS])
def test_equivalence_catches_a_broken_uart_twin(tmp_path, core_name, fname, good, bad):
    c = core(core_name)
    files = list(c.vhdl)
    idx = [p.name for p in files].index(fname)
    src = files[idx].read_text()
    assert good in src
    files[idx] = tmp_path / fname
    files[idx].write_text(src.replace(good, bad))
    # seq=1: a mutant fails at any induction depth, and the failing search is the slow part
    r = eda.equivalence(c, vhdl_override=files, seq=1, work=tmp_path / "bad")
    assert not r.ok and "ghdl synth failed" not in r.detail, r.detail


def test_uart_twins_are_equivalent(tmp_path):
    for name in ("uart", "uart_rx", "uart_tx", "sync_fifo"):
        r = eda.equivalence(core(name), work=tmp_path / name)
        assert r.ok, r.detail
