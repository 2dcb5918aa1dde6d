"""Every command-line tool answers a missing file with one line and a
non-zero exit, never a traceback (and before it touches a board)."""

from __future__ import annotations

import subprocess
import sys

import pytest

from torqueloop.spec.repo import REPO_ROOT

MISSING = "no/such/file"
PY = sys.executable
# nothing listens on port 9 (discard): a tool that connected before reading
# its file would report the link instead of the file
URL = "socket://127.0.0.1:9"

CASES = {
    "torqueloop config load": [PY, "-m", "torqueloop.cli", "-u", URL, "config", "load", MISSING + ".json"],
    "torqueloop upload": [PY, "-m", "torqueloop.cli", "-u", URL, "upload", MISSING + ".elf"],
    "characterize run": [PY, "-m", "torqueloop.study", "characterize", "run", MISSING],
    "characterize step5": [PY, "-m", "torqueloop.study", "characterize", "step5", MISSING + ".csv"],
    "characterize check": [PY, "-m", "torqueloop.study", "characterize", "check", MISSING + ".csv"],
    "characterize show": [PY, "-m", "torqueloop.study", "characterize", "show", MISSING + ".json"],
    "characterize export": [PY, "-m", "torqueloop.study", "characterize", "export", MISSING + ".json", "--out", "x.h"],
    "run_elf": [PY, "scripts/run_elf.py", MISSING + ".elf"],
    "upload": [PY, "scripts/upload.py", "--port", URL, MISSING + ".elf"],
}


@pytest.mark.parametrize("name", CASES)
def test_a_missing_file_is_one_line(name: str, tmp_path) -> None:
    cmd = [str(REPO_ROOT / c) if c.startswith("scripts/") else c for c in CASES[name]]
    r = subprocess.run(cmd, capture_output=True, text=True, cwd=tmp_path, timeout=60)
    err = r.stderr.strip()
    assert r.returncode != 0, (name, r.stdout, err)
    assert "Traceback" not in err, err
    assert len(err.splitlines()) == 1 and MISSING in err, err
    assert "127.0.0.1" not in err, f"{name} opened the link before reading its file: {err}"
    assert not (tmp_path / "x.h").exists()
