# SPDX-License-Identifier: MIT
"""The DE0-CV Quartus project: generated files and the project folder.

    python -m torqueloop.flow.quartus [--compile]    (make quartus: --compile)

``python -m torqueloop.flow.generate`` writes the generated files of the pin
table (:func:`products`; ``--check`` fails on a stale one); this module's
command creates the Quartus project in build/quartus (de0_cv_top.qpf + the
committed .qsf) and, with ``--compile``, compiles it when quartus_sh is on
PATH and fails on negative slack in the timing summary, otherwise prints the
commands for a machine that has it.  torqueloop/flow/constraints_check.py
(python -m torqueloop.flow constraints) checks the committed files against the board.
"""

from __future__ import annotations

import argparse
import re
import shutil
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path

from torqueloop.flow import board_files as board
from torqueloop.flow.licence import with_licence
from torqueloop.flow.manifest import REPO_ROOT, load_manifest
from torqueloop.spec import auth

PROJECT = "de0_cv_top"
#: interfaces of primitives that exist only inside Quartus (cyclonev_asmiblock): in the
#: Quartus top's manifest list for the linters, never in the Quartus project
LINT_ONLY = REPO_ROOT / "rtl" / "lint_only"


@dataclass(frozen=True)
class Product:
    path: Path
    text: str      # full new content


def is_lint_only(p: Path) -> bool:
    return p.resolve().is_relative_to(LINT_ONLY.resolve())


def project_sources(verilog: tuple[Path, ...] | list[Path]) -> list[Path]:
    """A core's Verilog list as the Quartus project takes it: without the vendor
    primitives' interfaces (Quartus has the primitives themselves)."""
    return [p for p in verilog if not is_lint_only(p)]


def top_sources(top: str) -> list[Path]:
    """The board top's Verilog sources for the Quartus project, in manifest order."""
    cores = load_manifest()
    if top not in cores:
        raise SystemExit(f"quartus: core '{top}' is not in rtl/manifest.toml yet "
                         "(it is added together with rtl/soc/tl_soc.v); cannot list the project's sources")
    return project_sources(cores[top].verilog)


def products(table: board.PinTable | None = None,
             board_pins: dict[str, board.BoardPin] | None = None,
             sources: list[Path] | None = None) -> list[Product]:
    """Every file generated from the pin table, with its new content."""
    table = table or board.load_pin_table()
    board_pins = board_pins or board.load_board_pins()
    problems = board.validate(table, board_pins)
    if problems:
        raise SystemExit("quartus: constraints/pins.toml is inconsistent:\n  " + "\n  ".join(problems))
    sources = sources if sources is not None else top_sources(table.board.quartus_top)
    out = [
        Product(board.QSF, with_licence(board.QSF.name, board.gen_qsf(table, board_pins, sources))),
        Product(board.SDC, with_licence(board.SDC.name, board.gen_sdc(table))),
    ]
    top_text = board.TOP_V.read_text()
    out.append(Product(board.TOP_V, board.replace_between(
        top_text, board.TOP_BEGIN, board.TOP_END, board.gen_top_gpio_block(table))))
    qtop = board.quartus_top_v(table)
    out.append(Product(qtop, with_licence(qtop.name, board.gen_quartus_top(table))))
    out.append(Product(board.CABLE_V, with_licence(board.CABLE_V.name, board.gen_cable_module(table))))
    if board.HARDWARE_MD.exists():
        md = board.HARDWARE_MD.read_text()
        out.append(Product(board.HARDWARE_MD, board.replace_between(
            md, board.MD_BEGIN, board.MD_END, board.gen_wiring_md(table, board_pins))))
    return out


def check_readmemh(image: Path, max_words: int | None = None) -> list[str]:
    """Problems of a $readmemh image (hex words, optional @address lines, //
    comments), and whether its words fit ``max_words``."""
    if not image.exists():
        return [f"{image} does not exist (build the firmware first: scripts/build_firmware.py)"]
    problems = []
    words = 0
    for n, line in enumerate(image.read_text().splitlines(), 1):
        body = line.split("//", 1)[0].strip()
        for word in body.split():
            if not re.fullmatch(r"@?[0-9a-fA-F_]{1,8}", word):
                problems.append(f"{image.name}:{n}: {word!r} is not a 32-bit hex word")
            elif not word.startswith("@"):
                words += 1
    if max_words is not None and words > max_words:
        problems.append(f"{image.name}: {words} words do not fit a memory of {max_words}")
    return problems


def memory_words() -> dict[str, int]:
    """Words of the memory each image parameter initialises (torqueloop/spec/regmap.toml sizes)."""
    from torqueloop.spec import regs

    return {"ROM_INIT": regs.BOOT_ROM_SIZE // 4, "RAM_INIT": regs.RAM_SIZE // 4}


def build_firmware() -> None:
    """The boot ROM named by the pin table: the bootloader with the servo
    firmware as its factory image (torqueloop.flow.boot_image)."""
    from torqueloop.flow import boot_image

    try:
        boot_image.main([])
    except RuntimeError as e:
        raise SystemExit(f"quartus: boot ROM build failed:\n{e}") from None


def write_project(project_dir: Path = board.QUARTUS_DIR) -> Path:
    """build/quartus/de0_cv_top.qpf + .qsf (a copy of the committed, checked one)."""
    if project_dir.resolve() != board.QUARTUS_DIR.resolve():
        raise SystemExit("quartus: the committed .qsf's relative paths assume build/quartus")
    table = board.load_pin_table()
    if table.firmware:
        build_firmware()
    sizes = memory_words()
    for name, image in table.firmware:
        for p in check_readmemh(image, sizes.get(name)):
            raise SystemExit(f"quartus: {name}: {p}")
    from torqueloop.flow import generate

    if generate.stale({str(p.path.relative_to(REPO_ROOT)): p.text for p in products(table)}):
        raise SystemExit("quartus: generated files are out of date; run "
                         "'.venv/bin/python -m torqueloop.flow.generate' and commit")
    project_dir.mkdir(parents=True, exist_ok=True)
    (project_dir / f"{PROJECT}.qpf").write_text(
        f"# Quartus project of the torqueloop board top, written by python -m torqueloop.flow.quartus\n"
        f'PROJECT_REVISION = "{PROJECT}"\n')
    shutil.copyfile(board.QSF, project_dir / f"{PROJECT}.qsf")
    return project_dir / f"{PROJECT}.qpf"


def sta_slacks(summary: str) -> list[tuple[str, float]]:
    """(analysis, worst slack in ns) of every entry of a Quartus timing
    summary (output_files/<revision>.sta.summary: "Type  : ..." then
    "Slack : ..." per clock and analysis)."""
    out: list[tuple[str, float]] = []
    kind = "?"
    for line in summary.splitlines():
        m = re.match(r"\s*Type\s*:\s*(.+?)\s*$", line)
        if m:
            kind = m.group(1)
            continue
        m = re.match(r"\s*Slack\s*:\s*(-?[0-9.]+)", line)
        if m:
            out.append((kind, float(m.group(1))))
    return out


def timing_verdict(summary_path: Path) -> tuple[bool, list[str]]:
    """(met, report lines) from the timing summary a compile wrote: met when
    the file lists at least one analysis and no slack is negative."""
    if not summary_path.exists():
        return False, [f"no timing summary at {summary_path} (did the compile reach the Timing Analyzer?)"]
    slacks = sta_slacks(summary_path.read_text())
    if not slacks:
        return False, [f"{summary_path.name} lists no slack"]
    lines = [f"{'FAIL' if v < 0 else 'ok  '} {kind}: slack {v:+.3f} ns" for kind, v in slacks]
    return all(v >= 0 for _, v in slacks), lines


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


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--compile", action="store_true", help="compile when quartus_sh is on PATH")
    ap.add_argument("--keyless", action="store_true",
                    help="build a boot ROM without a link key (a board that refuses every move)")
    args = ap.parse_args(argv)
    if auth.key_file_path(None) is None and not args.keyless:
        # A long compile ending in a board that refuses every move helps nobody: stop before it.
        print(f"[quartus] no link key: name the key file in ${auth.KEY_FILE_ENV} (`torqueloop key new FILE`; "
              "docs/security.md, 'Key provisioning'), or `make quartus KEYLESS=1` for a board that refuses "
              "motion, parameter changes and uploads", file=sys.stderr)
        return 2
    qpf = write_project()
    if not board.load_pin_table().firmware:
        print("[quartus] WARNING: constraints/pins.toml [firmware] names no ROM_INIT image: the boot ROM"
              " of this bitstream is empty and the CPU will run no program")
    return compile_project(qpf) if args.compile else 0


if __name__ == "__main__":
    sys.exit(main())
