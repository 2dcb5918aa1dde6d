# SPDX-License-Identifier: MIT
"""The layers of the Python side and the one direction their imports may go.

    spec                               the single sources, one definition of each equation
    host   oracles  sim_models   flow  the lab tool | core oracles | the plant | EDA flows
    sim                                co-simulation, simulated boards, the experiment's runs and report
    characterize                       the characterisation method and its bench
    cli   study                        the applications, side by side: the ``torqueloop`` lab tool |
                                       the studies (``torqueloop-study``: make run, make characterize)

A module may import its own layer and the layers its entry in ``ALLOWED``
names, nothing else of ours: never upward, never sideways between the
middle layers.  It may not load a file by path (importlib's
``spec_from_file_location``, ``runpy``, ``exec`` of a file) or edit
``sys.path``: what a module needs it imports by name.

:func:`violations` reads the sources (``ast``; nothing is imported), so a
function-level (lazy) import counts as much as a top-level one.

The leaves (``scripts/``, ``tests/``) may import any layer, but they load
nothing by path and edit no ``sys.path`` either, and ``tb/`` belongs to the
test benches: nothing outside ``tb/`` and ``tests/`` imports a module of
``tb/``, and ``tests/`` imports only ``tb/tbutil`` (a benchmark that runs a
bench's measurement hands its folder to ``flow.simrun.run(bench=...)``).
``make lint`` and tests/test_layers.py run it.
"""

from __future__ import annotations

import ast
import functools
from dataclasses import dataclass
from pathlib import Path

from torqueloop.flow.checks import finish
from torqueloop.spec.repo import REPO_ROOT

#: layer -> the layers it may import (besides itself)
ALLOWED: dict[str, frozenset[str]] = {
    "torqueloop.spec": frozenset(),
    "torqueloop.host": frozenset({"torqueloop.spec"}),
    "torqueloop.oracles": frozenset({"torqueloop.spec"}),
    "sim_models": frozenset({"torqueloop.spec"}),
    "torqueloop.flow": frozenset({"torqueloop.spec"}),
    "torqueloop.sim": frozenset({"torqueloop.spec", "torqueloop.host", "torqueloop.oracles", "sim_models",
                                 "torqueloop.flow"}),
    "torqueloop.characterize": frozenset({"torqueloop.spec", "torqueloop.host", "torqueloop.oracles",
                                          "sim_models", "torqueloop.flow", "torqueloop.sim"}),
    "torqueloop.cli": frozenset({"torqueloop.spec", "torqueloop.host", "torqueloop.oracles", "sim_models",
                                 "torqueloop.flow", "torqueloop.sim", "torqueloop.characterize"}),
    "torqueloop.study": frozenset({"torqueloop.spec", "torqueloop.host", "torqueloop.oracles", "sim_models",
                                   "torqueloop.flow", "torqueloop.sim", "torqueloop.characterize"}),
}
#: modules outside every layer that any module may import
SHARED = frozenset({"torqueloop"})          # the package's __init__ (version only)
PACKAGES = ("torqueloop", "sim_models")     # what counts as "ours"
LEAVES = ("scripts", "tests")               # entry points and unit tests: above every layer
TB = "tb"                                   # the test benches
#: what tests/ may import from tb/
TB_FOR_TESTS = frozenset({"tbutil"})


@dataclass(frozen=True)
class Violation:
    file: str
    line: int
    what: str

    def __str__(self) -> str:
        return f"{self.file}:{self.line}: {self.what}"


def layer_of(module: str) -> str | None:
    """The layer a dotted module name belongs to (None: not ours, or SHARED)."""
    best = None
    for layer in ALLOWED:
        if module == layer or module.startswith(layer + "."):
            if best is None or len(layer) > len(best):
                best = layer
    return best


def _module_name(path: Path, root: Path) -> str:
    rel = path.relative_to(root).with_suffix("")
    parts = list(rel.parts)
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


#: the nodes the checks look at
_CHECKED = (ast.Import, ast.ImportFrom, ast.Attribute, ast.Assign, ast.AugAssign)


@functools.lru_cache(maxsize=None)
def _nodes(text: str, filename: str) -> tuple[ast.AST, ...]:
    """The checked nodes of one file's text, parsed and walked once per text
    (the walk is most of a check's time, and the planted-mistake tests check
    the same tree a dozen times)."""
    return tuple(n for n in ast.walk(ast.parse(text, filename=filename)) if isinstance(n, _CHECKED))


def _imports(nodes: tuple[ast.AST, ...], module: str, is_pkg: bool) -> list[tuple[int, str]]:
    out = []
    for node in nodes:
        if isinstance(node, ast.Import):
            out += [(node.lineno, a.name) for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            if node.level:   # relative: resolve against this module's package
                base = module.split(".")
                base = base if is_pkg else base[:-1]
                base = base[:len(base) - node.level + 1]
                target = ".".join(base + ([node.module] if node.module else []))
            else:
                target = node.module or ""
            if layer_of(target) is not None:
                out.append((node.lineno, target))
            else:   # `from torqueloop import sim` imports the module torqueloop.sim
                out += [(node.lineno, f"{target}.{a.name}") for a in node.names]
    return out


def _path_tricks(nodes: tuple[ast.AST, ...]) -> list[tuple[int, str]]:
    out = []
    for node in nodes:
        if isinstance(node, ast.Attribute) and node.attr in ("spec_from_file_location", "run_path"):
            out.append((node.lineno, f"loads a file by path ({node.attr})"))
        elif isinstance(node, ast.Attribute) and node.attr in ("insert", "append", "extend") \
                and isinstance(node.value, ast.Attribute) and node.value.attr == "path" \
                and isinstance(node.value.value, ast.Name) and node.value.value.id == "sys":
            out.append((node.lineno, f"edits sys.path (sys.path.{node.attr})"))
        elif isinstance(node, (ast.Assign, ast.AugAssign)):
            targets = node.targets if isinstance(node, ast.Assign) else [node.target]
            for t in targets:
                t = t.value if isinstance(t, ast.Subscript) else t
                if isinstance(t, ast.Attribute) and t.attr == "path" and isinstance(t.value, ast.Name) \
                        and t.value.id == "sys":
                    out.append((node.lineno, "assigns sys.path"))
    return out


def tb_modules(root: Path = REPO_ROOT) -> frozenset[str]:
    """The top-level names a module of tb/ is imported by (tb/ and each bench
    folder go on the path of pytest and of the simulator's Python)."""
    return frozenset({TB} | {p.stem for p in (root / TB).rglob("*.py") if p.stem != "conftest"})


def _tb_imports(nodes: tuple[ast.AST, ...], tb: frozenset[str]) -> list[tuple[int, str]]:
    out = []
    for node in nodes:
        if isinstance(node, ast.Import):
            out += [(node.lineno, a.name) for a in node.names if a.name.split(".")[0] in tb]
        elif isinstance(node, ast.ImportFrom) and not node.level and node.module \
                and node.module.split(".")[0] in tb:
            out.append((node.lineno, node.module))
    return out


def leaf_violations(root: Path = REPO_ROOT, leaves: tuple[str, ...] = LEAVES) -> list[Violation]:
    """Files loaded by path, sys.path edits and imports from tb/ in the leaves."""
    tb = tb_modules(root)
    found: list[Violation] = []
    for leaf in leaves:
        for path in sorted((root / leaf).rglob("*.py")):
            rel = str(path.relative_to(root))
            nodes = _nodes(path.read_text(), rel)
            found += [Violation(rel, line, what) for line, what in _path_tricks(nodes)]
            for line, target in _tb_imports(nodes, tb):
                if leaf == "tests" and target.split(".")[0] in TB_FOR_TESTS:
                    continue
                found.append(Violation(rel, line, f"{leaf}/ imports {target} from tb/ (tb/ belongs to the test "
                                                  f"benches; tests/ may import only {', '.join(sorted(TB_FOR_TESTS))})"))
    return found


def violations(root: Path = REPO_ROOT, packages: tuple[str, ...] = PACKAGES,
               leaves: tuple[str, ...] = LEAVES) -> list[Violation]:
    """Every import against the direction, file loaded by path and sys.path
    edit in the packages under ``root``, and the leaves' (:func:`leaf_violations`)."""
    tb = tb_modules(root)
    found: list[Violation] = []
    for pkg in packages:
        for path in sorted((root / pkg).rglob("*.py")):
            module = _module_name(path, root)
            mine = layer_of(module)
            rel = str(path.relative_to(root))
            nodes = _nodes(path.read_text(), rel)
            for line, what in _path_tricks(nodes):
                found.append(Violation(rel, line, what))
            for line, target in _tb_imports(nodes, tb):
                found.append(Violation(rel, line, f"imports {target} from tb/ (the package needs no test bench)"))
            if mine is None:
                continue   # torqueloop/__init__.py
            allowed = ALLOWED[mine] | {mine} | SHARED
            for line, target in _imports(nodes, module, path.name == "__init__.py"):
                if not target.split(".")[0] in packages:
                    continue
                theirs = layer_of(target)
                if theirs is None:   # the package itself or its __init__'s names (SHARED)
                    continue
                if theirs not in allowed:
                    found.append(Violation(rel, line, f"{mine} imports {target} ({theirs}): "
                                                      f"against the layer direction"))
    return found + leaf_violations(root, leaves)


def main() -> int:
    bad = violations()
    return finish("layers", bad, f"import direction of torqueloop/ and sim_models/, and what scripts/ and tests/ "
                                 f"take from tb/ ({len(bad)} violations)")


if __name__ == "__main__":
    raise SystemExit(main())
