# SPDX-License-Identifier: MIT
"""The clockless e-stop path (rtl/board/tl_estop_gate.v) is glitch-free by
construction: synthesised, each bridge pin is exactly one 2-input AND of its
registered input and the KEY[0] pin, and nothing else.  (Its function - KEY[0]
pressed means every pin low, and no pin high without its input high - is
proven by Yosys SAT in make lint, tb/formal/estop_gate_props.v; the board top
is checked at the pins with no clock edge in tb/de0_cv_top.)  A 2-input AND
whose other input is low cannot rise when KEY[0] changes, so the only thing a
bouncing key can do to a pin is take it low."""

from __future__ import annotations

import json
import subprocess

import pytest

from torqueloop.spec.repo import REPO_ROOT

N = 8   # the board top's 4 inputs x 2 axes


def _netlist(tmp_path, extra: str = "") -> dict:
    out = tmp_path / "gate.json"
    script = (f"read_verilog {REPO_ROOT / 'rtl/board/tl_estop_gate.v'}\n{extra}"
              f"chparam -set N {N} tl_estop_gate\nsynth -top tl_estop_gate -flatten\n"
              f"opt_clean\nwrite_json {out}\n")
    subprocess.run(["yosys", "-q", "-p", script], check=True, capture_output=True, text=True)
    return json.loads(out.read_text())["modules"]["tl_estop_gate"]


def _check_one_and_per_pin(mod: dict) -> None:
    ports = mod["ports"]
    key = ports["key_n"]["bits"][0]
    din, dout = ports["drive_in"]["bits"], ports["drive_out"]["bits"]
    cells = list(mod["cells"].values())
    assert {c["type"] for c in cells} == {"$_AND_"}, f"cells {sorted({c['type'] for c in cells})}"
    assert len(cells) == N, f"{len(cells)} gates for {N} pins"
    for c in cells:
        a, b, y = c["connections"]["A"][0], c["connections"]["B"][0], c["connections"]["Y"][0]
        i = dout.index(y)                       # drives one pin ...
        assert {a, b} == {key, din[i]}, f"pin {i}: AND of {a}, {b}"   # ... from its input and the key only


def test_each_pin_is_one_and_of_its_input_and_the_key(tmp_path) -> None:
    _check_one_and_per_pin(_netlist(tmp_path))


def test_the_check_catches_a_gate_that_could_glitch(tmp_path) -> None:
    """Planted: a pin that also depends on a neighbouring input (an OR before
    the AND: two paths from the key to the pin) is not the one-gate shape."""
    src = tmp_path / "planted.v"
    src.write_text((REPO_ROOT / "rtl/board/tl_estop_gate.v").read_text().replace(
        "assign drive_out = drive_in & {N{key_n}};",
        "assign drive_out = drive_in & ({N{key_n}} | (drive_in >> 1));"))
    out = tmp_path / "p.json"
    subprocess.run(["yosys", "-q", "-p", f"read_verilog {src}\nchparam -set N {N} tl_estop_gate\n"
                    f"synth -top tl_estop_gate -flatten\nopt_clean\nwrite_json {out}\n"], check=True,
                   capture_output=True)
    mod = json.loads(out.read_text())["modules"]["tl_estop_gate"]
    with pytest.raises(AssertionError):
        _check_one_and_per_pin(mod)
