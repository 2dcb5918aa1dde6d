# SPDX-License-Identifier: MIT
"""A second, standards-strict front end over every Verilog core: slang (the
pyslang package), in make lint.

Verilator, Icarus and Yosys each accept things the standard does not say
(a name used before its declaration, a macro defined in another file of the
same command line); Quartus is a fourth reader nobody here can run.  slang
parses and elaborates each core of rtl/manifest.toml from its top, with the
core's header folders as include paths and each file its own compilation
unit - so a file that relies on another file's `define fails here, as it
could in Quartus - and ``-Wextra`` on.  Any error, and any warning not in
REVIEWED below, fails.
"""

from __future__ import annotations

import sys
from dataclasses import dataclass

from torqueloop.flow.manifest import REPO_ROOT, Core, load_manifest

#: warnings read and accepted, with the reason (slang's option names)
REVIEWED: dict[str, str] = {
    "empty-output-connection": "an output left open on purpose, written .port() "
                               "(the CPU's muldiv busy flag; Verilator's PINCONNECTEMPTY waiver says the same)",
}


@dataclass
class Report:
    core: str
    errors: list[str]
    warnings: list[str]
    waived: int

    @property
    def ok(self) -> bool:
        return not self.errors and not self.warnings


def check_core(c: Core, extra_args: list[str] = ()) -> Report:
    """Elaborate one core with slang; diagnostics as text lines."""
    from pyslang import DiagnosticEngine, DiagnosticSeverity, driver

    d = driver.Driver()
    d.addStandardArgs()
    args = ["slang", "--top", c.top, "-Wextra", *extra_args]
    args += [f"-I{p}" for p in c.include_dirs]
    args += [f"-G{k}={v}" for k, v in c.synth_params.items()]
    args += [str(p) for p in c.verilog_sources]
    if not d.parseCommandLine(" ".join(args), driver.CommandLineOptions()) or not d.processOptions():
        return Report(c.name, [f"slang did not accept the command line {' '.join(args)}"], [], 0)
    d.parseAllSources()
    comp = d.createCompilation()
    errors: list[str] = []
    warnings: list[str] = []
    waived = 0
    for diag in comp.getAllDiagnostics():
        text = DiagnosticEngine.reportAll(d.sourceManager, [diag]).strip()
        first = text.split("\n")[0].replace(str(REPO_ROOT) + "/", "")
        if diag.isError():
            errors.append(text.replace(str(REPO_ROOT) + "/", ""))
        elif any(f"[-W{opt}]" in first for opt in REVIEWED):
            waived += 1
        elif d.diagEngine.getSeverity(diag.code, diag.location) != DiagnosticSeverity.Ignored:
            warnings.append(text.replace(str(REPO_ROOT) + "/", ""))
    return Report(c.name, errors, warnings, waived)


def check_all(cores: dict[str, Core] | None = None) -> list[Report]:
    cores = cores if cores is not None else load_manifest()
    return [check_core(c) for c in cores.values() if c.verilog]


def main() -> int:
    reports = check_all()
    bad = [r for r in reports if not r.ok]
    for r in bad:
        for line in r.errors + r.warnings:
            print(line, file=sys.stderr)
    waived = sum(r.waived for r in reports)
    print(f"[strict] {'ok  ' if not bad else 'FAIL'} slang -Wextra elaborates {len(reports)} cores, "
          f"each file its own compilation unit: {sum(len(r.errors) for r in reports)} errors, "
          f"{sum(len(r.warnings) for r in reports)} unreviewed warnings ({waived} reviewed: "
          f"{', '.join(REVIEWED)})")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
