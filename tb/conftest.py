# SPDX-License-Identifier: MIT
"""pytest configuration shared by the cocotb test benches under tb/."""

import sys
from pathlib import Path

# Let test modules import shared helpers in tb/ (tbutil) when pytest runs them.
sys.path.insert(0, str(Path(__file__).resolve().parent))
