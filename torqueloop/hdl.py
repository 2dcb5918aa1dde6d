"""The HDL manifest (rtl/manifest.toml): which cores exist and their sources.

Every flow (lint, sim, synth, equivalence, Quartus project) reads the core
list from here, so adding a core is one edit.
"""

from __future__ import annotations

import tomllib
from dataclasses import dataclass, field
from pathlib import Path

REPO_ROOT = Path(__file__).resolve().parent.parent
MANIFEST = REPO_ROOT / "rtl" / "manifest.toml"


@dataclass(frozen=True)
class FormalCheck:
    """A property wrapper (Verilog with immediate asserts, read with -formal)
    that instantiates the core; proven by Yosys sat -tempinduct."""

    file: Path
    top: str
    depth: int = 20          # max induction length
    reset: str | None = None  # input held high in the first step (base case from reset)


@dataclass(frozen=True)
class Core:
    """One HDL core: its Verilog and VHDL sources and how the flows treat it."""

    name: str
    top: str
    verilog: tuple[Path, ...]
    vhdl: tuple[Path, ...]
    synth: bool = False
    equiv: bool = False
    synth_params: dict[str, int] = field(default_factory=dict)
    formal: tuple["FormalCheck", ...] = ()

    @property
    def has_vhdl(self) -> bool:
        return bool(self.vhdl)


def _paths(entries: list[str], core: str) -> tuple[Path, ...]:
    out = []
    for e in entries:
        p = REPO_ROOT / e
        if not p.is_file():
            raise FileNotFoundError(f"rtl/manifest.toml: core '{core}' names missing file {e}")
        out.append(p)
    return tuple(out)


def load_manifest(path: Path = MANIFEST) -> dict[str, Core]:
    """Parse the manifest; raise with the core's name on any missing file."""
    with open(path, "rb") as f:
        data = tomllib.load(f)
    cores: dict[str, Core] = {}
    for name, spec in data.get("core", {}).items():
        unknown = set(spec) - {"verilog", "vhdl", "top", "synth", "equiv", "synth_params", "formal"}
        if unknown:
            raise ValueError(f"rtl/manifest.toml: core '{name}' has unknown keys {sorted(unknown)}")
        cores[name] = Core(
            name=name,
            top=spec.get("top", name),
            verilog=_paths(spec.get("verilog", []), name),
            vhdl=_paths(spec.get("vhdl", []), name),
            synth=bool(spec.get("synth", False)),
            equiv=bool(spec.get("equiv", False)),
            synth_params=dict(spec.get("synth_params", {})),
            formal=tuple(
                FormalCheck(file=_paths([f["file"]], name)[0], top=f["top"],
                            depth=int(f.get("depth", 20)), reset=f.get("reset"))
                for f in spec.get("formal", [])
            ),
        )
    return cores


def core(name: str) -> Core:
    """The manifest entry for one core."""
    cores = load_manifest()
    if name not in cores:
        raise KeyError(f"core '{name}' is not in rtl/manifest.toml (have: {', '.join(sorted(cores))})")
    return cores[name]
