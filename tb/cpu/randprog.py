# SPDX-License-Identifier: MIT
"""Seeded random RV32IM instruction streams for the CPU-vs-ISS comparison.

The stream mixes every RV32I ALU and M-extension operation (with operands
biased towards the corner cases 0, 1, -1, -2^31 and 2^31-1 so that division
by zero and -2^31 / -1 occur), loads and stores of every width at aligned
addresses in a scratch area, forward branches and jumps (JAL, JALR), and
mscratch CSR accesses.  Sources often name the last destinations, so
results are used by the very next instruction (load-use, mul/div-use).  At the end every register is stored after the
scratch area; scratch area and registers together form the signature that
the core and the ISS must agree on word for word.
"""

from __future__ import annotations

import random

ALU_RR = ["add", "sub", "sll", "slt", "sltu", "xor", "srl", "sra", "or", "and"]
ALU_RI = ["addi", "slti", "sltiu", "xori", "ori", "andi"]
SHIFT_I = ["slli", "srli", "srai"]
MULDIV = ["mul", "mulh", "mulhsu", "mulhu", "div", "divu", "rem", "remu"]
LOADS = {"lb": 1, "lbu": 1, "lh": 2, "lhu": 2, "lw": 4}
STORES = {"sb": 1, "sh": 2, "sw": 4}
BRANCHES = ["beq", "bne", "blt", "bge", "bltu", "bgeu"]
CORNERS = [0, 1, -1, -(1 << 31), (1 << 31) - 1, 2, -2]

BASE_REG = 31      # points into the middle of the scratch area
LINK_REG = 30      # holds JALR targets
SCRATCH_BYTES = 1024
FREE = list(range(1, 30))


def generate(seed: int, count: int) -> str:
    """Assembly text of a random program of about ``count`` instructions."""
    rng = random.Random(seed)
    out = [f"# random instruction stream, seed {seed}, {count} instructions",
           "    .section .text.init, \"ax\"", "    .globl _start", "_start:"]
    for r in FREE:
        out.append(f"    li x{r}, {rng.choice(CORNERS) if rng.random() < 0.3 else rng.getrandbits(32)}")
    out.append(f"    la x{BASE_REG}, scratch + {SCRATCH_BYTES // 2}")
    label = 0

    recent: list[int] = []  # destinations just written: reuse them to create back-to-back dependences

    def reg() -> str:
        r = rng.choice(FREE)
        recent.append(r)
        del recent[:-2]
        return f"x{r}"

    def src() -> str:
        if recent and rng.random() < 0.4:
            return f"x{rng.choice(recent)}"
        return f"x{rng.choice(FREE + [0])}"

    def forward(jump: list[str], filler: str, skip: int) -> int:
        """``jump`` (which names the next label, .Lf{label}), ``skip`` filler
        instructions it jumps over, then that label; returns ``skip``."""
        nonlocal label
        out.extend(jump)
        out.extend(f"    {filler} {reg()}, {src()}, {rng.randint(-50, 50)}" for _ in range(skip))
        out.append(f".Lf{label}:")
        label += 1
        return skip

    n = 0
    while n < count:
        kind = rng.choices(["rr", "ri", "sh", "md", "ld", "st", "br", "jal", "jalr", "lui", "csr", "corner"],
                           [12, 8, 4, 6, 6, 6, 5, 2, 2, 2, 1, 8])[0]
        if kind == "rr":
            out.append(f"    {rng.choice(ALU_RR)} {reg()}, {src()}, {src()}")
        elif kind == "ri":
            imm = rng.choice([rng.randint(-2048, 2047), -1, 0, 2047, -2048])
            out.append(f"    {rng.choice(ALU_RI)} {reg()}, {src()}, {imm}")
        elif kind == "sh":
            out.append(f"    {rng.choice(SHIFT_I)} {reg()}, {src()}, {rng.randint(0, 31)}")
        elif kind == "md":
            out.append(f"    {rng.choice(MULDIV)} {reg()}, {src()}, {src()}")
        elif kind == "corner":
            # force a corner-case operand pair for the M extension
            a, b = rng.choice(FREE), rng.choice(FREE)
            out.append(f"    li x{a}, {rng.choice(CORNERS)}")
            out.append(f"    li x{b}, {rng.choice([0, -1, 1, -(1 << 31)])}")
            out.append(f"    {rng.choice(MULDIV[4:] if rng.random() < 0.6 else MULDIV)} {reg()}, x{a}, x{b}")
            n += 2
        elif kind in ("ld", "st"):
            op, size = rng.choice(list((LOADS if kind == "ld" else STORES).items()))
            off = rng.randrange(-SCRATCH_BYTES // 2, SCRATCH_BYTES // 2, size)
            if kind == "ld":
                out.append(f"    {op} {reg()}, {off}(x{BASE_REG})")
            else:
                out.append(f"    {op} {src()}, {off}(x{BASE_REG})")
        elif kind == "br":
            skip = rng.randint(0, 3)
            n += forward([f"    {rng.choice(BRANCHES)} {src()}, {src()}, .Lf{label}"], "addi", skip)
        elif kind == "jal":
            skip = rng.randint(0, 2)
            n += forward([f"    jal {src()}, .Lf{label}"], "xori", skip)
        elif kind == "jalr":
            skip = rng.randint(0, 2)
            rd = rng.choice(FREE + [0])
            n += 2 + forward([f"    la x{LINK_REG}, .Lf{label}", f"    jalr x{rd}, 0(x{LINK_REG})"], "ori", skip)
        elif kind == "lui":
            op = rng.choice(["lui", "auipc"])
            out.append(f"    {op} {reg()}, {rng.getrandbits(20)}")
        else:
            op = rng.choice(["csrrw", "csrrs", "csrrc"])
            out.append(f"    {op} {reg()}, mscratch, {src()}")
        n += 1

    out.append("    la x30, regs")
    out += [f"    sw x{r}, {4 * r}(x30)" for r in range(32) if r != 30]
    out += ["    li x1, 1", "    la x2, tohost", "    sw x1, 0(x2)", "1:  j 1b", ""]
    out.append("    .section .signature, \"aw\", @progbits")
    out.append("scratch:")
    out += [f"    .word {rng.getrandbits(32)}" for _ in range(SCRATCH_BYTES // 4)]
    out.append("regs: .zero 128")
    out += ["    .section .tohost, \"aw\", @progbits", "    .align 6", "    .globl tohost",
            "tohost: .word 0", "    .word 0", ""]
    return "\n".join(out)
