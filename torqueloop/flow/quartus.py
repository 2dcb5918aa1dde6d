# SPDX-License-Identifier: MIT
"""The DE0-CV Quartus project: generated files and the project folder.

``python -m torqueloop.flow.generate`` writes the generated files (and
``--check`` fails on a stale one), scripts/gen_quartus.py (make quartus)
writes the project folder; torqueloop/flow/constraints_check.py
(scripts/check_constraints.py) checks the committed files against the board.
"""

from __future__ import annotations

import difflib
import re
import shutil
from dataclasses import dataclass
from pathlib import Path

from torqueloop.flow import board_files as board
from torqueloop.flow.licence import with_licence
from torqueloop.flow.manifest import REPO_ROOT, load_manifest

PROJECT = "de0_cv_top"


@dataclass(frozen=True)
class Product:
    path: Path
    text: str      # full new content


def top_sources(top: str) -> list[Path]:
    """The board top's Verilog sources, in manifest order."""
    cores = load_manifest()
    if top not in cores:
        raise SystemExit(f"gen_quartus: core '{top}' is not in rtl/manifest.toml yet "
                         "(it is added together with rtl/soc/tl_soc.v); cannot list the project's sources")
    return list(cores[top].verilog)


def products(table: board.PinTable | None = None,
             board_pins: dict[str, board.BoardPin] | None = None,
             sources: list[Path] | None = None) -> list[Product]:
    """Every file generated from the pin table, with its new content."""
    table = table or board.load_pin_table()
    board_pins = board_pins or board.load_board_pins()
    problems = board.validate(table, board_pins)
    if problems:
        raise SystemExit("gen_quartus: constraints/pins.toml is inconsistent:\n  " + "\n  ".join(problems))
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


def stale(prods: list[Product]) -> list[tuple[Product, str]]:
    """(product, unified diff) for every product whose file differs."""
    out = []
    for p in prods:
        old = p.path.read_text() if p.path.exists() else ""
        if old != p.text:
            rel = p.path.relative_to(REPO_ROOT)
            diff = "".join(difflib.unified_diff(old.splitlines(True), p.text.splitlines(True),
                                                f"a/{rel}", f"b/{rel}"))
            out.append((p, diff))
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
        raise SystemExit(f"gen_quartus: boot ROM build failed:\n{e}") from None


def write_project(project_dir: Path = board.QUARTUS_DIR) -> Path:
    """build/quartus/de0_cv_top.qpf + .qsf (a copy of the committed, checked one)."""
    if project_dir.resolve() != board.QUARTUS_DIR.resolve():
        raise SystemExit("gen_quartus: the committed .qsf's relative paths assume build/quartus")
    table = board.load_pin_table()
    if table.firmware:
        build_firmware()
    sizes = memory_words()
    for name, image in table.firmware:
        for p in check_readmemh(image, sizes.get(name)):
            raise SystemExit(f"gen_quartus: {name}: {p}")
    drift = stale(products(table))
    if drift:
        raise SystemExit("gen_quartus: generated files are out of date; run "
                         "'.venv/bin/python -m torqueloop.flow.generate' and commit")
    project_dir.mkdir(parents=True, exist_ok=True)
    (project_dir / f"{PROJECT}.qpf").write_text(
        f"# Quartus project of the torqueloop board top, written by scripts/gen_quartus.py\n"
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

