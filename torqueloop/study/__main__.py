# SPDX-License-Identifier: MIT
"""python -m torqueloop.study: the ``torqueloop-study`` command."""

import sys

from torqueloop.study.cli import main

sys.exit(main())
