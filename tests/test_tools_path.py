# SPDX-License-Identifier: MIT
"""The same Verilator however the tests are started (torqueloop/flow/tools.py):
`make test`, `.venv/bin/python -m pytest`, or `pytest` in an activated
environment whose PATH finds Debian's Verilator 5.006 first."""

from __future__ import annotations

import os
import subprocess
import sys

import pytest

from torqueloop.flow import tools
from torqueloop.spec.repo import REPO_ROOT


def test_the_runner_sees_the_project_verilator_with_a_bare_path(tmp_path) -> None:
    if tools.tools_dir() is None:
        pytest.skip("no <venv>/tools/bin/verilator: make setup has not run in this environment")
    # PATH as a shell without the venv has it: /usr/bin (Debian's verilator) first
    env = {k: v for k, v in os.environ.items() if k not in ("VLT_VERSION", "VIRTUAL_ENV")}
    env["PATH"] = "/usr/local/bin:/usr/bin:/bin"
    probe = ("import shutil, subprocess; from torqueloop.flow import tools; tools.use_project_tools(); "
             "print(subprocess.run(['verilator', '--version'], capture_output=True, text=True).stdout)")
    r = subprocess.run([sys.executable, "-c", probe], env=env, capture_output=True, text=True, cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    major, minor = (int(x) for x in r.stdout.split()[1].split(".")[:2])
    assert (major, minor) >= (5, 36), r.stdout


def test_pytest_from_the_venv_python_builds_a_verilator_bench(tmp_path) -> None:
    """The reported failure: `.venv/bin/python -m pytest tb -k "... and verilator"`
    with Debian's Verilator first on PATH (the build failed with
    'clearEvalNeeded' is not a member of 'VerilatedVpi')."""
    if tools.tools_dir() is None:
        pytest.skip("no <venv>/tools/bin/verilator: make setup has not run in this environment")
    env = {k: v for k, v in os.environ.items() if k not in ("VLT_VERSION", "VIRTUAL_ENV", "PYTEST_XDIST_WORKER")}
    env["PATH"] = "/usr/local/bin:/usr/bin:/bin"
    r = subprocess.run([sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", "-p", "no:xdist",
                        "tb/sync_2ff", "-k", "verilator and w1r0"],
                       env=env, capture_output=True, text=True, cwd=REPO_ROOT, timeout=600)
    assert r.returncode == 0 and " passed" in r.stdout, r.stdout[-3000:] + r.stderr[-2000:]
