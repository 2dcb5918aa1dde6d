# SPDX-License-Identifier: MIT
"""The HDL manifest (rtl/manifest.toml): which cores exist and their sources.

Every flow (lint, sim, synth, equivalence, Quartus project) reads the core
list from here, so adding a core is one edit.
"""

from __future__ import annotations

import argparse
import tomllib
from dataclasses import dataclass, field
from pathlib import Path

from torqueloop.spec.repo import REPO_ROOT

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

    @property
    def include_dirs(self) -> tuple[Path, ...]:
        """Folders of the core's Verilog headers (.vh): every tool gets them as
        include paths, since each file that uses a header's names includes it
        itself rather than relying on the compile order."""
        return tuple(dict.fromkeys(p.parent for p in self.verilog if p.suffix == ".vh"))

    @property
    def verilog_sources(self) -> tuple[Path, ...]:
        """The Verilog files to compile: the list without the headers, which
        reach each file through its own `include."""
        return tuple(p for p in self.verilog if p.suffix != ".vh")


def _paths(entries: list[str], core: str) -> tuple[Path, ...]:
    out = []
    for e in entries:
        p = REPO_ROOT / e
        if not p.is_file():
            raise FileNotFoundError(f"rtl/manifest.toml: core '{core}' names missing file {e}")
        out.append(p)
    return tuple(out)


def _with_uses(specs: dict, name: str, lang: str, seen: tuple[str, ...] = ()) -> list[str]:
    """A core's sources with those of the cores it ``uses`` first (recursively),
    each file once, in dependency order; so a top never copies a list."""
    if name in seen:
        raise ValueError(f"rtl/manifest.toml: 'uses' cycle {' -> '.join((*seen, name))}")
    if name not in specs:
        raise KeyError(f"rtl/manifest.toml: core '{seen[-1]}' uses unknown core '{name}'")
    out: list[str] = []
    for used in specs[name].get("uses", []):
        out += _with_uses(specs, used, lang, (*seen, name))
    out += specs[name].get(lang, [])
    return list(dict.fromkeys(out))


def load_manifest(path: Path = MANIFEST) -> dict[str, Core]:
    """Parse the manifest; raise with the core's name on any missing file."""
    with open(path, "rb") as f:
        data = tomllib.load(f)
    specs = data.get("core", {})
    cores: dict[str, Core] = {}
    for name, spec in specs.items():
        unknown = set(spec) - {"verilog", "vhdl", "top", "synth", "equiv", "synth_params", "formal", "uses"}
        if unknown:
            raise ValueError(f"rtl/manifest.toml: core '{name}' has unknown keys {sorted(unknown)}")
        cores[name] = Core(
            name=name,
            top=spec.get("top", name),
            # A core has a language only if it declares sources in it itself;
            # then the cores it uses contribute theirs in that language too.
            verilog=_paths(_with_uses(specs, name, "verilog"), name) if "verilog" in spec else (),
            vhdl=_paths(_with_uses(specs, name, "vhdl"), name) if "vhdl" in spec else (),
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


def core_command_line(description: str, default: str, argv: list[str] | None = None
                      ) -> tuple[argparse.Namespace, dict[str, Core]]:
    """The command line of make lint and make synth: core names (checked
    against the manifest: an unknown one is a usage error, one line) and
    ``-j``.  Returns the arguments and the manifest."""
    ap = argparse.ArgumentParser(description=description)
    ap.add_argument("cores", nargs="*", help=f"only these cores (default: {default})")
    ap.add_argument("-j", "--jobs", type=int, default=2)
    args = ap.parse_args(argv)
    cores = load_manifest()
    unknown = [n for n in args.cores if n not in cores]
    if unknown:
        ap.error(f"no core {', '.join(unknown)} in rtl/manifest.toml (it has: {', '.join(cores)})")
    return args, cores
