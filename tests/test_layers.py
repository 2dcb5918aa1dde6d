# SPDX-License-Identifier: MIT
"""The Python side's layers import in one direction only (torqueloop.flow.layers)."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest

from torqueloop.flow import layers
from torqueloop.spec.repo import REPO_ROOT


def test_the_tree_imports_in_the_layer_direction() -> None:
    bad = layers.violations()
    assert not bad, "\n".join(map(str, bad))


def test_every_module_belongs_to_a_layer() -> None:
    for pkg in layers.PACKAGES:
        for path in (REPO_ROOT / pkg).rglob("*.py"):
            mod = ".".join(path.relative_to(REPO_ROOT).with_suffix("").parts).removesuffix(".__init__")
            assert layers.layer_of(mod) is not None or mod in layers.SHARED, mod


@pytest.fixture
def tree(tmp_path: Path) -> Path:
    """A copy of the packages to plant mistakes in."""
    for pkg in layers.PACKAGES:
        shutil.copytree(REPO_ROOT / pkg, tmp_path / pkg, ignore=shutil.ignore_patterns("__pycache__"))
    assert layers.violations(tmp_path) == []
    return tmp_path


@pytest.mark.parametrize("where, text, expect", [
    # upward: the single sources must not know the simulations
    ("torqueloop/spec/planted.py", "from torqueloop.sim import experiment\n", "torqueloop.spec imports torqueloop.sim"),
    # sideways, lazily inside a function: the host tool must not need the plant
    ("torqueloop/host/planted.py", "def f():\n    import sim_models.stepper\n", "torqueloop.host imports sim_models"),
    # relative import reaching up a level
    ("torqueloop/oracles/planted.py", "from ..characterize import method\n", "torqueloop.oracles imports torqueloop.characterize"),
    ("sim_models/planted.py", "from torqueloop import flow\n", "sim_models imports torqueloop.flow"),
    ("torqueloop/sim/planted.py", "import importlib.util\nspec = importlib.util.spec_from_file_location('x', 'y.py')\n",
     "loads a file by path"),
    ("torqueloop/flow/planted.py", "import sys\nsys.path.insert(0, 'tb')\n", "edits sys.path"),
])
def test_a_planted_mistake_is_caught(tree: Path, where: str, text: str, expect: str) -> None:
    (tree / where).write_text(text)
    found = layers.violations(tree)
    assert len(found) == 1 and expect in str(found[0]) and where in str(found[0]), found
