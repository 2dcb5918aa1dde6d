# SPDX-License-Identifier: MIT
"""Shared fixtures of the unit tests."""

import os
import random

import pytest


@pytest.fixture
def seed() -> int:
    """A fresh random seed per test, printed (pytest shows it on failure);
    TORQUELOOP_SEED=<n> reruns with a given one.  A fixture rather than a
    parametrize value: pytest-xdist needs every worker to collect the same
    test ids."""
    s = int(os.environ.get("TORQUELOOP_SEED", random.randrange(2**31)))
    print(f"seed {s} (rerun: TORQUELOOP_SEED={s})")
    return s
