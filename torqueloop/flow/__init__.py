# SPDX-License-Identifier: MIT
"""EDA flows and generators: the HDL manifest, the cocotb runner, lint,
synthesis and proofs, the Quartus project, and every file generated from a
single source (``python -m torqueloop.flow.generate --check``)."""
