# SPDX-License-Identifier: MIT
"""The CPU cores side by side, the multi-cycle tl_cpu and the pipelined
tl_cpu_pipe: CPI on a small integer benchmark (tb/cpu/progs/bench.c, -O2),
cycles per instruction class, Cyclone V resources and logic depth.  The
firmware's control iteration on both cores is bench_firmware's."""

from __future__ import annotations

import json
import re
import subprocess
import sys
import tempfile
from pathlib import Path

from torqueloop.flow import eda
from torqueloop.flow.manifest import REPO_ROOT, core

REPS = 64
#: instruction class -> one instance (repeated REPS times between two mcycle reads)
CLASSES = {
    "alu (add)": "add t2, t2, t3",
    "alu imm (addi)": "addi t2, t2, 1",
    "lui": "lui t2, 0x12345",
    "branch not taken": "bne x0, x0, .+8",
    "branch taken": "beq x0, x0, .+4",
    "jal": "jal x0, .+4",
    "load (lw)": "lw t2, 0(sp)",
    "store (sw)": "sw t2, 0(sp)",
    "mul": "mul t2, t3, t4",
    "div": "div t2, t3, t4",
    "csr read (mscratch)": "csrr t2, mscratch",
}


def class_program() -> str:
    out = ["    .section .text.init, \"ax\"", "    .globl _start", "_start:",
           "    la sp, __stack_top - 16", "    la s0, begin_signature",
           "    li t3, 123456789", "    li t4, -77",
           # overhead of the measurement itself: two back-to-back mcycle reads
           "    csrr t0, mcycle", "    csrr t1, mcycle", "    sub s1, t1, t0"]
    for i, insn in enumerate(CLASSES.values()):
        out += ["    csrr t0, mcycle", f"    .rept {REPS}", f"    {insn}", "    .endr",
                "    csrr t1, mcycle", "    sub t1, t1, t0", "    sub t1, t1, s1", f"    sw t1, {4 * i}(s0)"]
    out += ["    li t0, 1", "    la t1, tohost", "    sw t0, 0(t1)", "1:  j 1b",
            "    .section .signature, \"aw\", @progbits", f"    .zero {4 * len(CLASSES)}",
            "    .section .tohost, \"aw\", @progbits", "    .align 6", "    .globl tohost",
            "tohost: .word 0", "    .word 0", ""]
    return "\n".join(out)


def run_elf(elf: Path, *extra: str) -> str:
    proc = subprocess.run([sys.executable, str(REPO_ROOT / "scripts" / "run_elf.py"), str(elf), *extra],
                          capture_output=True, text=True)
    if proc.returncode != 0:
        raise RuntimeError(proc.stdout + proc.stderr)
    return proc.stdout


#: the cores: name in scripts/run_elf.py --core -> manifest core
CORES = {"multi": "cpu", "pipe": "cpu_pipe"}


def logic_depth(netlist: Path, top: str, skip_prefix: str | None = None) -> int:
    """Longest path in cells (LUTs, carry cells, DSPs) between flip-flops, block
    RAMs (registered reads) and ports: Yosys ltp after removing those cells
    (optionally also one submodule's cells).  Works around eda.synth_cyclonev's
    ltp selection, which reports -1."""
    src = netlist
    if skip_prefix:
        d = json.loads(netlist.read_text())
        m = d["modules"][top]
        m["cells"] = {k: v for k, v in m["cells"].items() if not k.startswith(skip_prefix)}
        src = Path(tempfile.mkdtemp()) / "netlist.json"
        src.write_text(json.dumps(d))
    out = subprocess.run(["yosys", "-p", f"read_json {src}; delete t:MISTRAL_FF t:MISTRAL_CLKBUF t:MISTRAL_M10K t:MISTRAL_MLAB; ltp"],
                         capture_output=True, text=True).stdout
    m = re.search(r"Longest topological path in \S+ \(length=(\d+)\)", out)
    return int(m.group(1)) if m else -1


def main() -> int:
    from torqueloop.flow.cpu_progs import PROGS, build

    elf = build("bench", [PROGS / "bench.c"], tag="bench", opt="-O2")
    with tempfile.TemporaryDirectory() as tmp:
        src = Path(tmp) / "classes.S"
        src.write_text(class_program())
        celf = build("classes", [src], tag="bench", crt0=False)
        cycles = {}
        for name in CORES:
            out = run_elf(elf, "--core", name)
            m = re.search(r"cycles=(\d+) instructions=(\d+) cpi=([\d.]+)", out)
            print(f"{name:5s} bench.c (-O2: CRC-32, insertion sort, 12x12 matrix product, itoa): "
                  f"{m.group(1)} cycles, {m.group(2)} instructions, CPI {m.group(3)}")
            sig = Path(tmp) / f"sig_{name}.txt"
            run_elf(celf, "--core", name, "--signature", str(sig))
            cycles[name] = [int(l, 16) for l in sig.read_text().split()]
    print(f"cycles per instruction by class (zero-wait-state RAM, {REPS} in a row, mcycle): "
          + "  ".join(f"{n:>6s}" for n in CORES))
    for i, cls in enumerate(CLASSES):
        print(f"  {cls:22s} " + "  ".join(f"{cycles[n][i] / REPS:6.2f}" for n in CORES))

    for name, cname in CORES.items():
        c = core(cname)
        row = eda.synth_cyclonev(c)
        if "error" in row:
            print(row["error"])
            return 1
        netlist = eda.BUILD / "synth" / cname / "netlist.json"
        depth = logic_depth(netlist, c.top)
        depth_core = logic_depth(netlist, c.top, "u_muldiv")
        print(f"{name:5s} Cyclone V (yosys synth_intel_alm): {row['luts']} LUTs, {row['carry_cells']} carry cells, "
              f"{row['ffs']} FFs, {row['dsp']} DSP blocks, {row['m10k']} M10K, {row['mlab']} MLAB")
        print(f"{name:5s} logic depth: {row.get('lut_levels', '?')} LUT levels (eda.lut_levels: carry hops free); "
              f"{depth} cells by ltp counting every carry-chain cell (without the multiplier: {depth_core})")
    return 0


if __name__ == "__main__":
    sys.exit(main())
