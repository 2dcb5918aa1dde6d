#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""The DE0-CV Quartus project from constraints/pins.toml and rtl/manifest.toml.

  gen_quartus.py --update     rewrite the committed products of the pin table:
                              constraints/de0_cv_top.qsf and .sdc, the GPIO
                              header block of rtl/board/de0_cv_top.v, the cable
                              harness of the board test wrappers and the wiring
                              table of docs/hardware.md
  gen_quartus.py --diff       show what --update would change (exit 1 if anything)
  gen_quartus.py --project    create the Quartus project in build/quartus
                              (de0_cv_top.qpf + the committed .qsf) and, with
                              --compile, compile it when quartus_sh is on PATH
                              and fail on negative slack in the timing summary;
                              otherwise print the commands for a machine that has it

make quartus (for the Makefile) = gen_quartus.py --project --compile.
"""

from __future__ import annotations

import argparse
import shutil
import subprocess
import sys
from pathlib import Path

from torqueloop.flow.board_files import load_pin_table
from torqueloop.flow.manifest import REPO_ROOT
from torqueloop.flow.quartus import PROJECT, products, stale, timing_verdict, write_project
from torqueloop.spec import auth


def compile_project(qpf: Path) -> int:
    """Compile when quartus_sh is on PATH and fail on negative slack; else
    print the commands for a machine that has Quartus."""
    cmd = ["quartus_sh", "--flow", "compile", PROJECT]
    rel = qpf.parent.relative_to(REPO_ROOT)
    summary = qpf.parent / "output_files" / f"{PROJECT}.sta.summary"
    if shutil.which("quartus_sh") is None:
        print(f"[quartus] project written: {qpf.relative_to(REPO_ROOT)} (boot ROM image built; docs/hardware.md, First compile)")
        print("[quartus] quartus_sh is not on PATH, so nothing was compiled. On a machine with Quartus Prime")
        print("[quartus] Lite 18.1 or later (Cyclone V needs 14.0+; 18.1 and 20.1 are the usual DE0-CV versions):")
        print(f"[quartus]   cd {rel} && {' '.join(cmd)}")
        print(f"[quartus]   grep -A2 'Type' {rel}/output_files/{PROJECT}.sta.summary   # every Slack must be >= 0")
        print(f"[quartus]   quartus_pgm -m jtag -o 'p;{rel}/output_files/{PROJECT}.sof'     # program the board over USB-Blaster")
        print("[quartus] or without Python: quartus_sh -t constraints/create_project.tcl compile")
        print(f"[quartus] or open {rel}/{PROJECT}.qpf in the Quartus GUI and press Compile.")
        print("[quartus] Then run make quartus again on that machine: it reads the timing summary and fails on negative slack.")
        return 0
    print(f"[quartus] {' '.join(cmd)}  (in {rel})", flush=True)
    rc = subprocess.run(cmd, cwd=qpf.parent).returncode
    if rc != 0:
        print(f"[quartus] compile failed (exit {rc}): see {rel}/output_files/*.rpt")
        return rc
    met, lines = timing_verdict(summary)
    for line in lines:
        print(f"[quartus] {line}")
    print(f"[quartus] timing {'met' if met else 'NOT met'}; bitstream {rel}/output_files/{PROJECT}.sof")
    return 0 if met else 1


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    g = ap.add_mutually_exclusive_group(required=True)
    g.add_argument("--update", action="store_true", help="rewrite the generated files")
    g.add_argument("--diff", action="store_true", help="show what --update would change")
    g.add_argument("--project", action="store_true", help="create build/quartus")
    ap.add_argument("--compile", action="store_true", help="with --project: compile when quartus_sh exists")
    ap.add_argument("--keyless", action="store_true",
                    help="with --project: build a boot ROM without a link key (a board that refuses every move)")
    args = ap.parse_args()
    if args.project:
        if auth.key_file_path(None) is None and not args.keyless:
            # A long compile ending in a board that refuses every move helps nobody: stop before it.
            print(f"[quartus] no link key: name the key file in ${auth.KEY_FILE_ENV} (`torqueloop key new FILE`; "
                  "docs/security.md, 'Key provisioning'), or `make quartus KEYLESS=1` for a board that refuses "
                  "motion, parameter changes and uploads", file=sys.stderr)
            return 2
        qpf = write_project()
        if not load_pin_table().firmware:
            print("[quartus] WARNING: constraints/pins.toml [firmware] names no ROM_INIT image: the boot ROM"
                  " of this bitstream is empty and the CPU will run no program")
        return compile_project(qpf) if args.compile else 0
    drift = stale(products())
    for p, diff in drift:
        if args.update:
            p.path.parent.mkdir(parents=True, exist_ok=True)
            p.path.write_text(p.text)
            print(f"[gen_quartus] wrote {p.path.relative_to(REPO_ROOT)}")
        else:
            sys.stdout.write(diff)
    if not drift:
        print("[gen_quartus] every generated file is up to date")
    return 1 if (drift and args.diff) else 0


if __name__ == "__main__":
    sys.exit(main())
