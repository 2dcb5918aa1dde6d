# SPDX-License-Identifier: MIT
"""The characterisation command as a lab uses it: a data folder per axis,
the loop (record a duty sweep where the tool says, run again), the written
configuration, the plots, and bad files refused with line and reason."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from torqueloop.characterize import BenchConstants, Sweep, load_config, write_sweep
from torqueloop.study.characterize_cli import EXIT_ERROR, EXIT_FAIL, EXIT_NEED_SWEEP, EXIT_OK, main

BENCH = BenchConstants(wheel_radius_m=0.02, theta_deg=90.0, supply_v=12.0)


def write_freq(path: Path, tau_max: float, f_cross: float) -> None:
    f = np.arange(50.0, 501.0, 50.0)
    t = tau_max / 2 * (1 + 0.3 * (f_cross - f) / f_cross)
    write_sweep(path, Sweep("frequency", "bench motor", BENCH, f, t, t / 1.1, duty_pct=50.0,
                            stall_torque_nm=tau_max, stall_current_a=tau_max / 1.1, force_given=True))


def write_duty(path: Path, f_hz: float, tau_max: float, pw0: float, bent: bool = False) -> None:
    d = np.arange(1.0, 100.0, 3.0)
    if bent:
        t = tau_max * (1 - np.exp(-d / 25.0))
    else:
        t = np.maximum(0.0, tau_max * (d - pw0) / (100 - pw0))
    write_sweep(path, Sweep("duty", "bench motor", BENCH, d, t, 0.02 * d, freq_hz=f_hz, force_given=True))


def test_lab_loop_to_a_loadable_configuration(tmp_path, capsys):
    data = tmp_path / "data"
    write_freq(data / "x" / "freq_sweep.csv", 2.4, 450.0)
    write_freq(data / "z" / "freq_sweep.csv", 2.08, 200.0)
    out = tmp_path / "cfg.json"
    argv = ["run", str(data), "--out", str(out), "--plots", str(tmp_path / "plots")]
    assert main(argv) == EXIT_NEED_SWEEP
    assert "record a duty sweep (1-99 %) at 450 Hz" in capsys.readouterr().out
    assert not out.exists()

    write_duty(data / "x" / "duty_448hz.csv", 448.4, 2.4, 11.0)
    write_duty(data / "z" / "duty_200hz.csv", 200.3, 2.08, 6.5, bent=True)
    assert main(argv) == EXIT_FAIL  # z is not linear at its only candidate
    assert not out.exists()

    write_duty(data / "z" / "duty_200hz.csv", 200.3, 2.08, 6.5)
    assert main(argv) == EXIT_OK
    cfg = load_config(out)
    x, z = cfg.axes["x"], cfg.axes["z"]
    assert (x.count_max, z.count_max) == (109, 244)
    assert x.pw0_counts == math.ceil(0.11 * 1023) and z.pw0_counts == math.ceil(0.065 * 1023)
    assert x.provenance["inputs"][0]["file"] == "x/freq_sweep.csv"
    assert len(x.provenance["inputs"][0]["sha256"]) == 64
    pngs = sorted(p.name for p in (tmp_path / "plots").glob("*.png"))
    assert "x_fig10_torque_vs_freq.png" in pngs and "z_fig11_torque_vs_duty_200hz.png" in pngs

    assert main(["show", str(out), "--registers"]) == EXIT_OK
    shown = capsys.readouterr().out
    assert "write AXIS0_FDIV       0x40004000 = 109" in shown  # x -> AXIS0 (regmap.toml)
    assert "write AXIS1_FDIV       0x40005000 = 244" in shown
    first = out.read_bytes()
    assert main(argv) == EXIT_OK
    assert out.read_bytes() == first  # same data, same file


def test_bad_file_stops_the_run_with_line_and_reason(tmp_path, capsys):
    data = tmp_path / "x"
    write_freq(data / "freq_sweep.csv", 2.4, 450.0)
    p = data / "freq_sweep.csv"
    lines = p.read_text().splitlines()
    i = next(k for k, s in enumerate(lines) if s.startswith("250,"))
    lines[i] = "250,nan,1.0"
    p.write_text("\n".join(lines) + "\n")
    assert main(["run", str(data), "--out", str(tmp_path / "c.json")]) == EXIT_ERROR
    err = capsys.readouterr().err
    assert f"freq_sweep.csv:{i + 1}: force_n is nan (NaN or infinite)" in err
    assert main(["check", str(p)]) == EXIT_ERROR


def test_exported_headers_compile(tmp_path):
    """The firmware header compiles against the generated register header
    and the Verilog `defines parse; both carry the configuration's counts."""
    import shutil
    import subprocess

    import pytest

    from torqueloop.flow.manifest import REPO_ROOT

    data = tmp_path / "data"
    write_freq(data / "x" / "freq_sweep.csv", 2.4, 450.0)
    write_duty(data / "x" / "duty.csv", 448.4, 2.4, 11.0)
    cfg = tmp_path / "cfg.json"
    assert main(["run", str(data), "--out", str(cfg)]) == EXIT_OK
    h, vh = tmp_path / "char.h", tmp_path / "char.vh"
    assert main(["export", str(cfg), "--out", str(h)]) == EXIT_OK
    assert main(["export", str(cfg), "--format", "verilog", "--out", str(vh)]) == EXIT_OK
    assert "#define TL_CHAR_AXIS0_FDIV 109u" in h.read_text()
    assert f"#define TL_CHAR_AXIS0_PWM_PW0 {math.ceil(0.11 * 1023)}u" in h.read_text()

    cc = shutil.which("riscv64-unknown-elf-gcc") or shutil.which("gcc")
    iv = shutil.which("iverilog")
    if not cc or not iv:
        pytest.skip("needs a C compiler and iverilog")
    src = tmp_path / "use.c"
    src.write_text('#include "char.h"\nvoid use(void) { tl_char_apply(); }\n')
    subprocess.run([cc, "-std=c11", "-ffreestanding", "-Wall", "-Werror", "-fsyntax-only",
                    "-I", str(REPO_ROOT / "firmware" / "include"), "-I", str(tmp_path), str(src)], check=True)
    v = tmp_path / "use.v"
    v.write_text(  # noqa: E501
        '`include "char.vh"\nmodule use_char; initial $display("FDIV=%0d W=%0d", `TL_CHAR_AXIS0_FDIV, $bits(`TL_CHAR_AXIS0_FDIV)); endmodule\n')
    subprocess.run([iv, "-g2005", "-I", str(tmp_path), "-o", str(tmp_path / "a.out"), str(v)], check=True)
    out = subprocess.run(["vvp", str(tmp_path / "a.out")], capture_output=True, text=True, check=True).stdout
    assert "FDIV=109 W=16" in out
