#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""The characterisation method (paper II.B) as a command: bench sweeps in,
the configuration (PWM frequency divider count, dead zone) out.
See docs/characterization.md; `characterize.py --help` for the sub-commands."""

from __future__ import annotations

import sys

from torqueloop.characterize.cli import main

if __name__ == "__main__":
    sys.exit(main())
