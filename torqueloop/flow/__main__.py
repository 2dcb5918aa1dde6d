# SPDX-License-Identifier: MIT
"""One entry for the flows: ``python -m torqueloop.flow COMMAND [options]``.

    gen [--check|--diff]   every generated file (flow/generate.py: the one registry of writers)
    lint [CORE ...]        Verilator -Wall, GHDL, Yosys check, equivalence and safety proofs (flow/lint.py)
    strict                 the second, standards-strict Verilog front end (flow/strict.py)
    hdl-rules              the Quartus-safety rules (flow/hdl_rules.py)
    constraints            the board constraints against the board and the top (flow/constraints_check.py)
    layers                 the import direction of the Python side (flow/layers.py)
    quartus [--compile]    the Quartus project in build/quartus (flow/quartus.py; make quartus)
    firmware               the servo firmware build (flow/firmware.py; make firmware)
"""

from __future__ import annotations

import importlib
import sys

COMMANDS = {"gen": "generate", "lint": "lint", "strict": "strict", "hdl-rules": "hdl_rules",
            "constraints": "constraints_check", "layers": "layers", "quartus": "quartus", "firmware": "firmware"}


def main(argv: list[str]) -> int:
    if not argv or argv[0] in ("-h", "--help"):
        print(__doc__)
        return 0 if argv else 2
    name = COMMANDS.get(argv[0])
    if name is None:
        print(f"torqueloop.flow: unknown command {argv[0]!r} (known: {', '.join(COMMANDS)})", file=sys.stderr)
        return 2
    module = importlib.import_module(f"torqueloop.flow.{name}")
    sys.argv = [f"python -m torqueloop.flow {argv[0]}", *argv[1:]]   # each command parses its own options
    return int(module.main())


sys.exit(main(sys.argv[1:]))
