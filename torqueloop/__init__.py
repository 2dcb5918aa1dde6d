# SPDX-License-Identifier: MIT
"""torqueloop: FPGA servo controller for DC-motor ball-screw stages.

Python side of the project: the HDL manifest and simulation runner used by
the test benches, and (in later modules) the host tool.
"""

__version__ = "0.1.0"
