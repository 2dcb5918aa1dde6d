# SPDX-License-Identifier: MIT
"""pytest, however started (make test, .venv/bin/python -m pytest, pytest in
an activated environment): the project's tools first on PATH
(torqueloop/flow/tools.py), so every test sees the same Verilator."""

from torqueloop.flow.tools import use_project_tools

use_project_tools()
