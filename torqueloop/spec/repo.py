# SPDX-License-Identifier: MIT
"""Where the source checkout is.  Only the flows, simulations and tests use
it: an installed host tool never reads files outside the package."""

from __future__ import annotations

from pathlib import Path

REPO_ROOT = Path(__file__).resolve().parents[2]
BUILD_ROOT = REPO_ROOT / "build"
