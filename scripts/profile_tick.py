# SPDX-License-Identifier: MIT
"""Where the control iteration's cycles go: tl_servo_tick under the firmware
bench's load (firmware/tests/tick_harness.c) on the RV32 instruction-set
simulator (torqueloop/oracles/rv32.py), each instruction charged the
pipelined core's cycles (docs/cpu.md, "Cycles per instruction", tl_cpu_pipe),
the worst period attributed to the functions the iteration inlines.

    python scripts/profile_tick.py [--case step|trap|short|board] [--ticks N] [--dither AMP] [--kvff Q16] [--kaff Q16] [--lines]

A model, not the RTL: the decoder registers are plain memory with no wait
states, and the interrupt's own bookkeeping around the iteration (main.c) is
not counted.  It ranks changes in seconds where the bench's Verilator run
(scripts/benches/bench_firmware.py) takes minutes; the bench has the last word.
"""

from __future__ import annotations

import argparse
import collections
import os
import subprocess
import sys
import tempfile
from pathlib import Path

from torqueloop.flow import firmware as F
from torqueloop.oracles.rv32 import Memory, Rv32, load_elf, read_elf
from torqueloop.spec import regs
from torqueloop.spec.system import SYSTEM

HARNESS = F.FW / "tests" / "tick_harness.c"
CASES = {"step": (0, 0, 200), "trap": (1, 0, 200), "short": (1, 1, 400), "board": (2, 0, 22000)}

# tl_cpu_pipe's cycles per instruction (docs/cpu.md, with the registered fetch): 1 for ALU, loads,
# stores, CSR reads and forward branches not taken; a load's result used by the next instruction +2,
# by the one after +1; a taken forward branch, jalr or a mispredicted backward branch 4; jal and a
# backward branch taken 3 unless the branch target buffer (8 entries, direct-mapped on pc[4:2], tag
# pc[31:5], written by every jal and backward branch D predicts) holds them, then 1
LOAD_USE = {1: 2, 2: 1}
BRANCH_TAKEN_FWD, BRANCH_MISS_BACK, JALR = 4, 4, 4
JUMP_PREDICTED, JUMP_IN_BTB = 3, 1
CSR_WRITE, MUL = 6, 3
BTB_ENTRIES = 8


def build(case: str, ticks: int, out: Path, dither: int = 0, kvff: int = 0, kaff: int = 0, tick0: int = 0) -> Path:
    mode, short, _ = CASES[case]
    elf = out / f"tick_{case}.elf"
    # the board case's Table 1 PID gains and no-load speeds, from their one definition
    pid = [v for g in SYSTEM.table1["PID"] for v in g.micro()]
    board = [f"-DTABLE1_PID={{{','.join(map(str, pid))}}}",
             f"-DNO_LOAD_CPS={{{','.join(str(a.no_load_cps) for a in SYSTEM.axes)}}}"]
    srcs = [str(s) for s in F.SOURCES if s.name != "main.c"] + [str(HARNESS)]
    cmd = [F.CC, *F.CFLAGS, "-g", f"-DMODE={mode}", f"-DSHORT={short}", f"-DNTICKS={ticks}", f"-DDITHER_AMP={dither}",
           f"-DKVFF_Q16={kvff}", f"-DKAFF_Q16={kaff}", f"-DTICK0={tick0}", *board,
           *(f"-I{i}" for i in F.INCLUDES), "-T", str(F.FW / "common" / "link.ld"), "-Wl,--gc-sections",
           "-Wl,--no-warn-rwx-segments", "-o", str(elf), *srcs, F.libgcc()]
    r = subprocess.run(cmd, capture_output=True, text=True)
    if r.returncode:
        raise RuntimeError(f"harness build failed:\n{r.stderr[-2000:]}")
    return elf


def div_cycles(insn: int, a: int, b: int) -> int:
    """A divide's cycles on tl_cpu_pipe: its two-steps-a-cycle divider (rtl/cpu/tl_cpu_muldiv.v, RADIX4)
    takes 1 + 16 + 1 cycles, or 1 + 1 + 12 + 1 skipping 8 leading quotient bits when the top byte of
    the dividend's magnitude is below the divisor; E one more."""
    if not (insn >> 12) & 1:                                   # DIV, REM: magnitudes
        a, b = (a if a < 1 << 31 else (1 << 32) - a), (b if b < 1 << 31 else (1 << 32) - b)
    return 1 + (1 + 1 + 12 + 1 if a >> 24 < b else 1 + 16 + 1)


def cycles_of(insn: int, pc: int, next_pc: int, since_load: int, load_rd: int, btb: list,
              operands: tuple[int, int] = (0, 0)) -> int:
    """An instruction's cycles; ``operands``: rs1's and rs2's values before it ran (a divide's
    cycles depend on them)."""
    op, f3 = insn & 0x7F, (insn >> 12) & 7
    rs1, rs2 = (insn >> 15) & 31, (insn >> 20) & 31
    uses = {rs1, rs2} if op in (0x33, 0x23, 0x63) else ({rs1} if op in (0x13, 0x03, 0x67, 0x73) else set())
    c = 1 + (LOAD_USE.get(since_load, 0) if load_rd and load_rd in uses else 0)
    if op == 0x6F or (op == 0x63 and insn >> 31):     # jal, backward branch: predicted taken
        slot = (pc >> 2) % BTB_ENTRIES
        hit = btb[slot] == pc
        btb[slot] = pc
        taken = next_pc != (pc + 4) & 0xFFFFFFFF
        c += (JUMP_IN_BTB if hit else JUMP_PREDICTED) - 1 if taken else BRANCH_MISS_BACK - 1
    elif op == 0x63:
        c += BRANCH_TAKEN_FWD - 1 if next_pc != (pc + 4) & 0xFFFFFFFF else 0
    elif op == 0x67:
        c += JALR - 1
    elif op == 0x33 and insn >> 25 == 1:
        c += (MUL if f3 < 4 else div_cycles(insn, *operands)) - 1
    elif op == 0x73 and (f3 == 1 or (f3 in (2, 3) and rs1 != 0)):
        c += CSR_WRITE - 1
    return c


def profile(elf_path: Path) -> list[tuple[int, collections.Counter]]:
    """Per call of tl_servo_tick: its cycles and the cycles per pc."""
    elf = read_elf(elf_path)
    mem = Memory()
    mem.add_ram(regs.RAM_BASE, regs.RAM_SIZE)
    mem.add_ram(regs.PERIPH_BASE, 0x10000)   # the registers, as plain memory
    mem.add_ram(0, 0x10000)                  # the boot ROM's key slot (empty)
    load_elf(mem, elf)
    sim = Rv32(mem, pc=elf.entry)
    tick, tohost = elf.symbols["tl_servo_tick"], elf.symbols["tohost"]
    ticks, cur, total, ret, active = [], collections.Counter(), 0, 0, False
    load_rd, since = 0, 9
    btb = [None] * BTB_ENTRIES   # the pc of the jump each entry holds (the BTB outlives a call)
    for _ in range(50_000_000):
        pc = sim.pc
        if not active and pc == tick:
            active, ret, total, cur = True, sim.x[1], 0, collections.Counter()
        elif active and pc == ret:
            active = False
            ticks.append((total, cur))
        insn = mem.load(pc, 4)
        operands = (sim.x[(insn >> 15) & 31], sim.x[(insn >> 20) & 31])
        sim.step()
        st = sim.last_store
        if st is not None and st[0] == tohost and st[2]:
            if st[2] & 0x7FFFFFFF:
                raise RuntimeError(f"a fault tripped in the harness run: {st[2]:#x}")
            return ticks
        if active:
            since += 1
            c = cycles_of(insn, pc, sim.pc, since, load_rd, btb, operands)
            if insn & 0x7F == 0x03:
                load_rd, since = (insn >> 7) & 31, 0
            cur[pc] += c
            total += c
    raise RuntimeError("the harness did not finish")


def where(elf: Path, pcs: list[int]) -> dict[int, list[tuple[str, str]]]:
    """pc -> inline chain [(function, file:line) innermost first]."""
    out = subprocess.run(["riscv64-unknown-elf-addr2line", "-e", str(elf), "-f", "-i", "-a", *map(hex, pcs)],
                         capture_output=True, text=True, check=True).stdout.splitlines()
    info: dict[int, list[tuple[str, str]]] = {}
    k, pc = 0, 0
    while k < len(out):
        if out[k].startswith("0x"):
            pc = int(out[k], 16)
            info[pc] = []
            k += 1
        else:
            info[pc].append((out[k], out[k + 1].split("/")[-1].split(" ")[0]))
            k += 2
    return info


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--case", choices=sorted(CASES), default="step")
    ap.add_argument("--ticks", type=int, help="control periods to run (default: the case's)")
    ap.add_argument("--dither", type=int, default=0, metavar="AMP",
                    help="DITHER_AMP on both axes, PWM steps 0..1023 (half-period 2 samples; default 0: off)")
    ap.add_argument("--kvff", type=int, default=0, metavar="Q16",
                    help="KVFF_Q16 on both axes (velocity feed-forward, 0..16777215; default 0: off)")
    ap.add_argument("--kaff", type=int, default=0, metavar="Q16",
                    help="KAFF_Q16 on both axes (acceleration feed-forward, 0..16777215; default 0: off)")
    ap.add_argument("--tick0", type=int, default=0, metavar="N",
                    help="the period count the run starts from, 0..3 (default 0): which runaway check "
                         "(docs/safety.md, 'Runaway at 20 kHz') runs in the periods the moves make dear")
    ap.add_argument("--lines", action="store_true", help="also the source lines, dearest first")
    a = ap.parse_args()
    ticks_n = CASES[a.case][2] if a.ticks is None else a.ticks
    if ticks_n < 1:
        print("profile_tick: --ticks must be at least 1", file=sys.stderr)
        return 2
    if not 0 <= a.tick0 <= 3:
        print("profile_tick: --tick0 must be 0..3", file=sys.stderr)
        return 2
    if not 0 <= a.dither <= 1023:
        print("profile_tick: --dither must be 0..1023 PWM steps", file=sys.stderr)
        return 2
    if not (0 <= a.kvff <= 0xFF_FFFF and 0 <= a.kaff <= 0xFF_FFFF):
        print("profile_tick: --kvff and --kaff must be 0..16777215 (q16)", file=sys.stderr)
        return 2
    with tempfile.TemporaryDirectory() as tmp:
        try:
            elf = build(a.case, ticks_n, Path(tmp), a.dither, a.kvff, a.kaff, a.tick0)
            ticks = profile(elf)
        except RuntimeError as e:
            print(f"profile_tick: {e}", file=sys.stderr)
            return 1
        cyc = [t for t, _ in ticks]
        worst = max(range(len(cyc)), key=cyc.__getitem__)
        print(f"{a.case}: {len(cyc)} periods, worst {cyc[worst]} cycles (period {worst}), "
              f"mean {sum(cyc) / len(cyc):.0f} (tl_cpu_pipe model, tl_servo_tick alone)")
        cur = ticks[worst][1]
        info = where(elf, sorted(cur))
        by_fn: collections.Counter = collections.Counter()
        by_line: collections.Counter = collections.Counter()
        for pc, c in cur.items():
            chain = info.get(pc) or [("?", "?")]
            by_fn[chain[0][0]] += c
            by_line[chain[0][1]] += c
        for fn, c in by_fn.most_common():
            print(f"{c:6d}  {fn}")
        if a.lines:
            print("source lines:")
            for ln, c in by_line.most_common(40):
                print(f"{c:6d}  {ln}")
    return 0


if __name__ == "__main__":
    try:
        sys.exit(main())
    except BrokenPipeError:     # the reader stopped early (`profile_tick.py | head -1`): what it read was printed
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())   # no second error at exit's flush
        sys.exit(0)
