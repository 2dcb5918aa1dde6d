# SPDX-License-Identifier: MIT
"""The proofs that guard freq_div and pwm_torque can fail: a deliberately
broken VHDL twin must fail the VHDL/Verilog equivalence proof, and a
deliberately broken Verilog core must fail the SAT safety properties."""

from dataclasses import replace

import pytest

from torqueloop.flow import eda
from torqueloop.flow.manifest import core


def _mutate(text: str, old: str, new: str) -> str:
    assert text.count(old) == 1, f"mutation anchor not found once: {old!r}"
    return text.replace(old, new)


@pytest.mark.parametrize("name, old, new", [
    # freq_div: a divisor write that also restarts the count
    ("freq_div", "div_q <= unsigned(div_in);", "div_q <= unsigned(div_in) + 1;"),
    # pwm_torque: the direction latched on every tick, not only at a period start
    ("pwm_torque_equiv", "dir_n  <= dir_next when start = '1' else dir_q;",
     "dir_n  <= dir_next when tick = '1' else dir_q;"),
])
def test_equivalence_catches_a_broken_vhdl_twin(tmp_path, name, old, new):
    c = core(name)
    f = tmp_path / c.vhdl[0].name
    f.write_text(_mutate(c.vhdl[0].read_text(), old, new))
    assert eda.equivalence(c, work=tmp_path / "good").ok
    assert not eda.equivalence(c, vhdl_override=[f], work=tmp_path / "bad").ok


@pytest.mark.parametrize("k, old, new", [
    # enable/fault no longer stop the bridge: the safe-state property must fail
    (0, "wire         run_n  = ~stop & (start | run_q);", "wire         run_n  = start | run_q;"),
    # duty latched on any tick: the period-boundary property must fail
    (1, "wire [N-1:0] duty_n = start ? duty_next : duty_q;", "wire [N-1:0] duty_n = tick ? duty_next : duty_q;"),
    # a full-scale duty that drops one tick per period
    (2, "wire         on_n   = (pcnt_n < duty_n);", "wire         on_n   = (pcnt_n < duty_n) & (pcnt_n != 0);"),
])
def test_properties_catch_a_broken_core(tmp_path, k, old, new):
    # Own names: the proof's files go to build/formal/<name>/, and the cases may run in parallel.
    c = core("pwm_torque")
    assert all(r.ok for r in eda.prove_properties(replace(c, name=f"pwm_torque_unit{k}"))), \
        "the real core must prove"
    f = tmp_path / "pwm_torque.v"
    f.write_text(_mutate(c.verilog[0].read_text(), old, new))
    broken = replace(c, name=f"pwm_torque_mutant{k}", verilog=(f,))
    assert not all(r.ok for r in eda.prove_properties(broken))
