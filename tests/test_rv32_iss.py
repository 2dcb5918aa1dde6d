# SPDX-License-Identifier: MIT
"""The RV32IM ISS (torqueloop/oracles/rv32.py), the CPU's oracle, checked on its own:
spec tables for the M extension, numpy as an independent integer model,
trap and interrupt rules of the privileged spec, and a C program whose
results the host compiler computes natively."""

from __future__ import annotations

import random
import shutil
import subprocess

import numpy as np
import pytest

from torqueloop.oracles import rv32
from torqueloop.oracles.rv32 import MASK32, Memory, Rv32

BASE = 0x8000_0000


def r_type(f7: int, rs2: int, rs1: int, f3: int, rd: int, op: int = 0x33) -> int:
    return (f7 << 25) | (rs2 << 20) | (rs1 << 15) | (f3 << 12) | (rd << 7) | op


def i_type(imm: int, rs1: int, f3: int, rd: int, op: int) -> int:
    return ((imm & 0xFFF) << 20) | (rs1 << 15) | (f3 << 12) | (rd << 7) | op


def machine(*words: int) -> Rv32:
    mem = Memory()
    mem.add_ram(BASE, 4096)
    for i, w in enumerate(words):
        mem.store(BASE + 4 * i, 4, w)
    return Rv32(mem, pc=BASE)


def exec_rr(f7: int, f3: int, a: int, b: int) -> int:
    m = machine(r_type(f7, 2, 1, f3, 3))
    m.x[1], m.x[2] = a & MASK32, b & MASK32
    m.step()
    assert m.last_trap is None
    return m.x[3]


# RISC-V unprivileged spec, table "Semantics for division by zero and division overflow"
@pytest.mark.parametrize("a,b,div,divu,rem,remu", [
    (7, 0, MASK32, MASK32, 7, 7),
    (-7, 0, MASK32, MASK32, -7 & MASK32, -7 & MASK32),
    (-(1 << 31), -1, 1 << 31, 0, 0, -(1 << 31) & MASK32),
    (-7, 2, -3 & MASK32, (((-7) & MASK32) // 2), -1 & MASK32, 1),
])
def test_division_corner_cases_match_the_spec_table(a, b, div, divu, rem, remu):
    assert exec_rr(1, 4, a, b) == div
    assert exec_rr(1, 5, a, b) == divu
    assert exec_rr(1, 6, a, b) == rem
    assert exec_rr(1, 7, a, b) == remu


@pytest.mark.filterwarnings("ignore::RuntimeWarning")
def test_alu_and_multiply_agree_with_numpy():
    seed = random.getrandbits(32)
    print(f"seed {seed}")
    rng = np.random.default_rng(seed)
    vals = rng.integers(0, 1 << 32, size=(300, 2), dtype=np.uint64)
    vals[:20] = [[0, 0], [MASK32, 1], [1 << 31, MASK32], [MASK32, MASK32], [1 << 31, 1 << 31]] * 4
    for a, b in vals.tolist():
        ua, ub = np.uint32(a), np.uint32(b)
        sa, sb = ua.view(np.int32), ub.view(np.int32)
        sh = int(b) & 31
        expect = {
            (0, 0): int(ua + ub), (0x20, 0): int(ua - ub), (0, 1): int(ua << np.uint32(sh)),
            (0, 2): int(sa < sb), (0, 3): int(ua < ub), (0, 4): int(ua ^ ub),
            (0, 5): int(ua >> np.uint32(sh)), (0x20, 5): int(np.int32(sa >> np.int32(sh)).view(np.uint32)),
            (0, 6): int(ua | ub), (0, 7): int(ua & ub),
            (1, 0): int(np.uint64(a) * np.uint64(b)) & MASK32,
            (1, 1): int((np.int64(sa) * np.int64(sb)) >> 32) & MASK32,
            (1, 3): int((np.uint64(a) * np.uint64(b)) >> np.uint64(32)),
        }
        with np.errstate(over="ignore"):
            for (f7, f3), want in expect.items():
                assert exec_rr(f7, f3, a, b) == want & MASK32, (f7, f3, hex(a), hex(b))


def test_misaligned_load_traps_precisely():
    m = machine(i_type(1, 1, 2, 5, 0x03))  # lw x5, 1(x1)
    m.mtvec = BASE + 0x100
    m.x[1], m.x[5] = BASE + 0x40, 1234
    m.step()
    assert (m.mcause, m.mepc, m.mtval, m.pc, m.x[5]) == (4, BASE, BASE + 0x41, BASE + 0x100, 1234)


def test_interrupt_priority_vectoring_and_mret():
    m = machine(0x3020_0073)  # mret
    m.mtvec = (BASE + 0x200) | 1  # vectored
    m.mie = (1 << 3) | (1 << 7) | (1 << 11)
    m.mip_lines = (1 << 3) | (1 << 7) | (1 << 11)
    m.mstatus |= rv32.MSTATUS_MIE
    m.step()  # MEI first
    assert m.mcause == (1 << 31) | 11 and m.pc == BASE + 0x200 + 4 * 11 and m.mepc == BASE
    assert not m.mstatus & rv32.MSTATUS_MIE and m.mstatus & rv32.MSTATUS_MPIE
    m.step()  # interrupts masked now; the zero word at the vector is an illegal instruction
    assert m.mcause == 2 and not m.mstatus & rv32.MSTATUS_MPIE  # MPIE took MIE = 0
    m.pc, m.mepc = BASE, BASE + 8
    m.mstatus |= rv32.MSTATUS_MPIE
    m.step()  # mret: MIE <- MPIE
    assert m.pc == BASE + 8 and m.mstatus & rv32.MSTATUS_MIE
    m.mip_lines = 1 << 7
    m.step()
    assert m.mcause == (1 << 31) | 7


@pytest.mark.skipif(shutil.which("riscv64-unknown-elf-gcc") is None or shutil.which("gcc") is None,
                    reason="needs the RISC-V and the host compiler")
@pytest.mark.parametrize("name,words", [("bench", 16), ("cstress", 24)])
def test_c_program_matches_host_compiled_results(tmp_path, name, words):
    """A C test program's signature on the ISS equals the same C compiled for the host."""
    from torqueloop.flow.cpu_progs import PROGS, RAM_BASE, RAM_BYTES, build

    elf = build(name, [PROGS / f"{name}.c"], tag="unit")
    iss = rv32.run_iss(elf, RAM_BASE, RAM_BYTES)
    assert iss.tohost == 1
    harness = tmp_path / "host_main.c"
    harness.write_text(
        '#include <stdio.h>\n#include <stdint.h>\nextern volatile uint32_t sig[];\n'
        'int bench_main(void);\nint main(void) { int r = bench_main();\n'
        '  for (int i = 0; i < WORDS; i++) printf("%u\\n", (unsigned)sig[i]); return r; }\n')
    exe = tmp_path / "bench_host"
    obj = tmp_path / f"{name}.o"
    subprocess.run(["gcc", "-O2", "-std=c11", "-Dmain=bench_main", "-c", str(PROGS / f"{name}.c"), "-o", str(obj)],
                   check=True)
    subprocess.run(["gcc", "-O2", f"-DWORDS={words}", str(harness), str(obj), "-o", str(exe)], check=True)
    host = [int(l) for l in subprocess.run([str(exe)], capture_output=True, text=True, check=True).stdout.split()]
    assert host == iss.signature[:words]
