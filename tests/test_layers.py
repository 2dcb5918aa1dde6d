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


@pytest.fixture(scope="module")
def clean_tree(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A copy of the packages, the leaves and the test benches' Python to plant mistakes in."""
    root = tmp_path_factory.mktemp("tree")
    for pkg in (*layers.PACKAGES, *layers.LEAVES, layers.TB):
        shutil.copytree(REPO_ROOT / pkg, root / pkg,
                        ignore=lambda d, names: [n for n in names if n == "__pycache__" or
                                                 ((Path(d) / n).is_file() and not n.endswith(".py"))])
    assert layers.violations(root) == []
    return root


@pytest.fixture
def tree(clean_tree: Path):
    """The copy; what a test plants in it is taken out afterwards."""
    before = {p: p.read_bytes() for p in clean_tree.rglob("*.py")}
    yield clean_tree
    for p in clean_tree.rglob("*.py"):
        if p not in before:
            p.unlink()
        elif p.read_bytes() != before[p]:
            p.write_bytes(before[p])


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
    # the two applications stand side by side
    ("torqueloop/study/planted.py", "from torqueloop import cli\n", "torqueloop.study imports torqueloop.cli"),
    # tb/ belongs to the test benches: not the package, not a script, and of it tests take only tbutil
    ("torqueloop/sim/planted.py", "import tbutil\n", "imports tbutil from tb/"),
    ("scripts/benches/bench_planted.py", "def main():\n    from test_firmware import DEFINES\n",
     "scripts/ imports test_firmware from tb/"),
    ("tests/test_planted.py", "import cpu_progs\n", "tests/ imports cpu_progs from tb/"),
    ("scripts/planted.py", "import sys\nsys.path.insert(0, 'tb/cpu')\n", "edits sys.path"),
    ("tests/test_planted.py", "import importlib.util\nimportlib.util.spec_from_file_location('g', 'scripts/g.py')\n",
     "loads a file by path"),
])
def test_a_planted_mistake_is_caught(tree: Path, where: str, text: str, expect: str) -> None:
    (tree / where).write_text(text)
    found = layers.violations(tree)
    assert len(found) == 1 and expect in str(found[0]) and where in str(found[0]), found


def test_the_lab_tool_does_not_import_the_studies(tree: Path) -> None:
    (tree / "torqueloop" / "cli.py").write_text("def main():\n    from torqueloop.study import experiment\n")
    found = layers.violations(tree)
    assert len(found) == 1 and "torqueloop.cli imports torqueloop.study" in str(found[0]), found


def test_tests_may_import_tbutil(tree: Path) -> None:
    (tree / "tests" / "test_planted.py").write_text("import tbutil\n")
    assert layers.violations(tree) == []
