# SPDX-License-Identifier: MIT
"""RV32IM + Zicsr instruction-set simulator, machine mode only: the oracle of the CPU core.

Written from the RISC-V unprivileged spec (RV32I, M) and the privileged
spec (machine-mode CSRs, traps, mret), not from rtl/cpu.  One call to
:meth:`Rv32.step` executes one instruction or takes one trap, like the
core's architectural state changes one instruction at a time.

What the model fixes where the spec leaves a choice (the core makes the same
choices, see docs/cpu.md):
  * mtval: the faulting address for misaligned and access-fault traps, the
    instruction word for illegal instructions, the pc for ebreak, 0 for ecall.
  * mtvec: direct (MODE 0) and vectored (MODE 1) modes; BASE is 4-byte aligned.
  * mstatus: only MIE (bit 3), MPIE (bit 7) and MPP (bits 12:11, always 11).
  * FENCE, FENCE.I and WFI execute as no-ops.
  * Unknown CSRs and writes to read-only CSRs raise illegal instruction.
"""

from __future__ import annotations

import struct
from dataclasses import dataclass, field
from pathlib import Path

MASK32 = 0xFFFF_FFFF

# Exception causes (privileged spec, mcause with interrupt bit clear)
CAUSE_MISALIGNED_FETCH = 0
CAUSE_FETCH_FAULT = 1
CAUSE_ILLEGAL = 2
CAUSE_BREAKPOINT = 3
CAUSE_MISALIGNED_LOAD = 4
CAUSE_LOAD_FAULT = 5
CAUSE_MISALIGNED_STORE = 6
CAUSE_STORE_FAULT = 7
CAUSE_ECALL_M = 11
# Interrupt codes (mcause with bit 31 set) and their mip/mie bit numbers
IRQ_MSI = 3
IRQ_MTI = 7
IRQ_MEI = 11

# CSR addresses
CSR_MSTATUS = 0x300
CSR_MISA = 0x301
CSR_MIE = 0x304
CSR_MTVEC = 0x305
CSR_MSCRATCH = 0x340
CSR_MEPC = 0x341
CSR_MCAUSE = 0x342
CSR_MTVAL = 0x343
CSR_MIP = 0x344
CSR_MCYCLE = 0xB00
CSR_MINSTRET = 0xB02
CSR_MCYCLEH = 0xB80
CSR_MINSTRETH = 0xB82
CSR_CYCLE = 0xC00
CSR_TIME = 0xC01
CSR_INSTRET = 0xC02
CSR_CYCLEH = 0xC80
CSR_TIMEH = 0xC81
CSR_INSTRETH = 0xC82
CSR_MVENDORID = 0xF11
CSR_MARCHID = 0xF12
CSR_MIMPID = 0xF13
CSR_MHARTID = 0xF14

#: misa for RV32IM: MXL = 1 (32 bit), extensions I and M
MISA_RV32IM = (1 << 30) | (1 << 8) | (1 << 12)
MSTATUS_MIE = 1 << 3
MSTATUS_MPIE = 1 << 7
MSTATUS_MPP = 3 << 11
MIE_WRITABLE = (1 << IRQ_MSI) | (1 << IRQ_MTI) | (1 << IRQ_MEI)


def sext(value: int, bits: int) -> int:
    """Sign-extend the low ``bits`` of ``value`` to a Python int."""
    value &= (1 << bits) - 1
    return value - (1 << bits) if value >> (bits - 1) else value


def signed(x: int) -> int:
    return sext(x, 32)


class Trap(Exception):
    """A synchronous exception raised while executing one instruction."""

    def __init__(self, cause: int, tval: int = 0) -> None:
        super().__init__(f"cause {cause} tval {tval:#x}")
        self.cause = cause
        self.tval = tval & MASK32


@dataclass
class Region:
    """A byte-addressed memory region: RAM (writable) or ROM."""

    base: int
    data: bytearray
    writable: bool = True

    def contains(self, addr: int, size: int) -> bool:
        return self.base <= addr and addr + size <= self.base + len(self.data)


@dataclass
class Memory:
    """The address space as a list of regions; anything else is an access fault."""

    regions: list[Region] = field(default_factory=list)

    def add_ram(self, base: int, size: int) -> Region:
        r = Region(base, bytearray(size))
        self.regions.append(r)
        return r

    def _find(self, addr: int, size: int) -> Region | None:
        for r in self.regions:
            if r.contains(addr, size):
                return r
        return None

    def load(self, addr: int, size: int) -> int | None:
        r = self._find(addr, size)
        if r is None:
            return None
        off = addr - r.base
        return int.from_bytes(r.data[off:off + size], "little")

    def store(self, addr: int, size: int, value: int) -> bool:
        r = self._find(addr, size)
        if r is None or not r.writable:
            return False
        off = addr - r.base
        r.data[off:off + size] = (value & ((1 << (8 * size)) - 1)).to_bytes(size, "little")
        return True

    def write_bytes(self, addr: int, blob: bytes) -> None:
        r = self._find(addr, len(blob))
        if r is None:
            raise ValueError(f"segment {addr:#x}+{len(blob):#x} outside memory")
        off = addr - r.base
        r.data[off:off + len(blob)] = blob


class Rv32:
    """Architectural state of one RV32IM machine-mode hart and its execution.

    ``mip_external`` holds the levels of the MEIP/MTIP/MSIP lines the platform
    drives; :meth:`step` takes a pending enabled interrupt before the next
    instruction, in the priority order MEI > MSI > MTI.
    """

    def __init__(self, mem: Memory, pc: int = 0, hart_id: int = 0) -> None:
        self.mem = mem
        self.pc = pc & MASK32
        self.x = [0] * 32
        self.hart_id = hart_id
        self.mstatus = MSTATUS_MPP
        self.mie = 0
        self.mip_lines = 0
        self.mtvec = 0
        self.mepc = 0
        self.mcause = 0
        self.mtval = 0
        self.mscratch = 0
        self.cycle = 0
        self.instret = 0
        self.time = 0
        # Set by a store: (addr, size, value) of the last store executed.
        self.last_store: tuple[int, int, int] | None = None
        self.last_trap: tuple[int, int] | None = None
        self._instret_written = False

    # --- CSRs -------------------------------------------------------------
    def csr_read(self, a: int) -> int:
        table = {
            CSR_MSTATUS: lambda: self.mstatus,
            CSR_MISA: lambda: MISA_RV32IM,
            CSR_MIE: lambda: self.mie,
            CSR_MIP: lambda: self.mip_lines & MIE_WRITABLE,
            CSR_MTVEC: lambda: self.mtvec,
            CSR_MEPC: lambda: self.mepc,
            CSR_MCAUSE: lambda: self.mcause,
            CSR_MTVAL: lambda: self.mtval,
            CSR_MSCRATCH: lambda: self.mscratch,
            CSR_MCYCLE: lambda: self.cycle & MASK32,
            CSR_MCYCLEH: lambda: (self.cycle >> 32) & MASK32,
            CSR_MINSTRET: lambda: self.instret & MASK32,
            CSR_MINSTRETH: lambda: (self.instret >> 32) & MASK32,
            CSR_CYCLE: lambda: self.cycle & MASK32,
            CSR_CYCLEH: lambda: (self.cycle >> 32) & MASK32,
            CSR_INSTRET: lambda: self.instret & MASK32,
            CSR_INSTRETH: lambda: (self.instret >> 32) & MASK32,
            CSR_TIME: lambda: self.time & MASK32,
            CSR_TIMEH: lambda: (self.time >> 32) & MASK32,
            CSR_MVENDORID: lambda: 0,
            CSR_MARCHID: lambda: 0,
            CSR_MIMPID: lambda: 0,
            CSR_MHARTID: lambda: self.hart_id,
        }
        if a not in table:
            raise KeyError(a)
        return table[a]() & MASK32

    def csr_write(self, a: int, v: int) -> None:
        v &= MASK32
        if a == CSR_MSTATUS:
            self.mstatus = (v & (MSTATUS_MIE | MSTATUS_MPIE)) | MSTATUS_MPP
        elif a == CSR_MIE:
            self.mie = v & MIE_WRITABLE
        elif a == CSR_MTVEC:
            # BASE 4-byte aligned; MODE 0 (direct) or 1 (vectored); MODE >= 2 reserved -> direct
            self.mtvec = (v & ~3) | (v & 1)
        elif a == CSR_MEPC:
            self.mepc = v & ~3
        elif a == CSR_MCAUSE:
            self.mcause = v
        elif a == CSR_MTVAL:
            self.mtval = v
        elif a == CSR_MSCRATCH:
            self.mscratch = v
        elif a == CSR_MCYCLE:
            self.cycle = (self.cycle & ~MASK32) | v
        elif a == CSR_MCYCLEH:
            self.cycle = (self.cycle & MASK32) | (v << 32)
        elif a in (CSR_MINSTRET, CSR_MINSTRETH):
            self._instret_written = True
        if a == CSR_MINSTRET:
            self.instret = (self.instret & ~MASK32) | v
        elif a == CSR_MINSTRETH:
            self.instret = (self.instret & MASK32) | (v << 32)
        # MISA and MIP (the lines are inputs) ignore writes: WARL

    # --- traps --------------------------------------------------------------
    def _trap(self, cause: int, tval: int, interrupt: bool) -> None:
        self.mepc = self.pc
        self.mcause = ((1 << 31) | cause) if interrupt else cause
        self.mtval = 0 if interrupt else tval
        mie = self.mstatus & MSTATUS_MIE
        self.mstatus = MSTATUS_MPP | (MSTATUS_MPIE if mie else 0)
        base = self.mtvec & ~3
        vectored = (self.mtvec & 3) == 1
        self.pc = (base + 4 * cause) & MASK32 if (interrupt and vectored) else base
        self.last_trap = (self.mcause, self.mtval)

    def pending_interrupt(self) -> int | None:
        if not self.mstatus & MSTATUS_MIE:
            return None
        pend = self.mip_lines & self.mie
        for code in (IRQ_MEI, IRQ_MSI, IRQ_MTI):
            if pend >> code & 1:
                return code
        return None

    # --- execution -----------------------------------------------------------
    def step(self) -> None:
        """Take a pending interrupt, or execute one instruction (or its exception)."""
        self.last_store = None
        self.last_trap = None
        irq = self.pending_interrupt()
        if irq is not None:
            self._trap(irq, 0, True)
            return
        self._instret_written = False
        try:
            self._execute()
            # A CSR write to minstret(h) takes effect after the writing
            # instruction's own increment (privileged spec), i.e. it wins.
            if not self._instret_written:
                self.instret = (self.instret + 1) & ((1 << 64) - 1)
        except Trap as t:
            self._trap(t.cause, t.tval, False)

    def _wr(self, rd: int, v: int) -> None:
        if rd:
            self.x[rd] = v & MASK32

    def _load(self, addr: int, size: int) -> int:
        if addr % size:
            raise Trap(CAUSE_MISALIGNED_LOAD, addr)
        v = self.mem.load(addr, size)
        if v is None:
            raise Trap(CAUSE_LOAD_FAULT, addr)
        return v

    def _store(self, addr: int, size: int, v: int) -> None:
        if addr % size:
            raise Trap(CAUSE_MISALIGNED_STORE, addr)
        if not self.mem.store(addr, size, v):
            raise Trap(CAUSE_STORE_FAULT, addr)
        self.last_store = (addr, size, v & ((1 << (8 * size)) - 1))

    def _jump(self, target: int) -> None:
        target &= MASK32
        if target & 3:
            raise Trap(CAUSE_MISALIGNED_FETCH, target)
        self.pc = target

    def _execute(self) -> None:
        pc = self.pc
        if pc & 3:
            raise Trap(CAUSE_MISALIGNED_FETCH, pc)
        insn = self.mem.load(pc, 4)
        if insn is None:
            raise Trap(CAUSE_FETCH_FAULT, pc)
        illegal = Trap(CAUSE_ILLEGAL, insn)
        opcode = insn & 0x7F
        rd = (insn >> 7) & 31
        f3 = (insn >> 12) & 7
        rs1 = (insn >> 15) & 31
        rs2 = (insn >> 20) & 31
        f7 = insn >> 25
        a = self.x[rs1]
        b = self.x[rs2]
        imm_i = sext(insn >> 20, 12)
        imm_s = sext(((insn >> 25) << 5) | ((insn >> 7) & 31), 12)
        imm_b = sext(((insn >> 31) << 12) | (((insn >> 7) & 1) << 11)
                     | (((insn >> 25) & 63) << 5) | (((insn >> 8) & 15) << 1), 13)
        imm_u = insn & 0xFFFF_F000
        imm_j = sext(((insn >> 31) << 20) | (((insn >> 12) & 255) << 12)
                     | (((insn >> 20) & 1) << 11) | (((insn >> 21) & 1023) << 1), 21)
        nxt = (pc + 4) & MASK32

        if opcode == 0x37:  # LUI
            self._wr(rd, imm_u)
        elif opcode == 0x17:  # AUIPC
            self._wr(rd, pc + imm_u)
        elif opcode == 0x6F:  # JAL
            self._jump(pc + imm_j)
            self._wr(rd, nxt)
            return
        elif opcode == 0x67:  # JALR
            if f3:
                raise illegal
            self._jump((a + imm_i) & ~1)
            self._wr(rd, nxt)
            return
        elif opcode == 0x63:  # branches
            conds = {0: a == b, 1: a != b, 4: signed(a) < signed(b), 5: signed(a) >= signed(b),
                     6: a < b, 7: a >= b}
            if f3 not in conds:
                raise illegal
            if conds[f3]:
                self._jump(pc + imm_b)
                return
        elif opcode == 0x03:  # loads
            addr = (a + imm_i) & MASK32
            if f3 == 0:
                self._wr(rd, sext(self._load(addr, 1), 8))
            elif f3 == 1:
                self._wr(rd, sext(self._load(addr, 2), 16))
            elif f3 == 2:
                self._wr(rd, self._load(addr, 4))
            elif f3 == 4:
                self._wr(rd, self._load(addr, 1))
            elif f3 == 5:
                self._wr(rd, self._load(addr, 2))
            else:
                raise illegal
        elif opcode == 0x23:  # stores
            addr = (a + imm_s) & MASK32
            if f3 > 2:
                raise illegal
            self._store(addr, 1 << f3, b)
        elif opcode == 0x13:  # OP-IMM
            shamt = rs2
            if f3 == 1 and f7 != 0:
                raise illegal
            if f3 == 5 and f7 not in (0, 0x20):
                raise illegal
            self._wr(rd, self._alu(f3, f7 == 0x20 and f3 == 5, a, imm_i & MASK32 if f3 not in (1, 5) else shamt))
        elif opcode == 0x33:  # OP and M extension
            if f7 == 1:
                self._wr(rd, self._muldiv(f3, a, b))
            elif f7 == 0 or (f7 == 0x20 and f3 in (0, 5)):
                self._wr(rd, self._alu(f3, f7 == 0x20, a, b))
            else:
                raise illegal
        elif opcode == 0x0F:  # FENCE (f3 0), FENCE.I (f3 1): no caches, no-ops
            if f3 not in (0, 1):
                raise illegal
        elif opcode == 0x73:
            self._system(insn, f3, rd, rs1, a)
            return
        else:
            raise illegal
        self.pc = nxt

    @staticmethod
    def _alu(f3: int, alt: bool, a: int, b: int) -> int:
        if f3 == 0:
            return (a - b if alt else a + b) & MASK32
        if f3 == 1:
            return (a << (b & 31)) & MASK32
        if f3 == 2:
            return int(signed(a) < signed(b))
        if f3 == 3:
            return int(a < (b & MASK32))
        if f3 == 4:
            return (a ^ b) & MASK32
        if f3 == 5:
            return (signed(a) >> (b & 31)) & MASK32 if alt else a >> (b & 31)
        if f3 == 6:
            return (a | b) & MASK32
        return a & b & MASK32

    @staticmethod
    def _muldiv(f3: int, a: int, b: int) -> int:
        sa, sb = signed(a), signed(b)
        if f3 == 0:
            return (a * b) & MASK32
        if f3 == 1:
            return ((sa * sb) >> 32) & MASK32
        if f3 == 2:
            return ((sa * b) >> 32) & MASK32
        if f3 == 3:
            return ((a * b) >> 32) & MASK32
        if f3 == 4:  # DIV: round toward zero; /0 -> -1; overflow -> -2^31
            if b == 0:
                return MASK32
            if sa == -(1 << 31) and sb == -1:
                return a
            q = abs(sa) // abs(sb)
            return (-q if (sa < 0) != (sb < 0) else q) & MASK32
        if f3 == 5:
            return MASK32 if b == 0 else a // b
        if f3 == 6:  # REM: sign of the dividend; /0 -> dividend; overflow -> 0
            if b == 0:
                return a
            if sa == -(1 << 31) and sb == -1:
                return 0
            r = abs(sa) % abs(sb)
            return (-r if sa < 0 else r) & MASK32
        return a if b == 0 else a % b

    def _system(self, insn: int, f3: int, rd: int, rs1: int, a: int) -> None:
        illegal = Trap(CAUSE_ILLEGAL, insn)
        if f3 == 0:
            if insn == 0x0000_0073:
                raise Trap(CAUSE_ECALL_M, 0)
            if insn == 0x0010_0073:
                raise Trap(CAUSE_BREAKPOINT, self.pc)
            if insn == 0x3020_0073:  # MRET
                mpie = self.mstatus & MSTATUS_MPIE
                self.mstatus = MSTATUS_MPP | MSTATUS_MPIE | (MSTATUS_MIE if mpie else 0)
                self.pc = self.mepc
                return
            if insn == 0x1050_0073:  # WFI: a hint here, no sleep
                self.pc = (self.pc + 4) & MASK32
                return
            raise illegal
        if f3 == 4:
            raise illegal
        csr = insn >> 20
        src = rs1 if f3 & 4 else a  # the immediate forms use the rs1 field as zimm
        # CSRRW/I always write; CSRRS/C(I) write only if rs1 (zimm) != 0.
        writes = (f3 & 3) == 1 or rs1 != 0
        try:
            old = self.csr_read(csr)
        except KeyError:
            raise illegal from None
        if writes and (csr >> 10) == 3:
            raise illegal  # read-only CSR
        if writes:
            op = f3 & 3
            new = src if op == 1 else (old | src if op == 2 else old & ~src)
            self.csr_write(csr, new)
        self._wr(rd, old)
        self.pc = (self.pc + 4) & MASK32


# --- ELF loading ------------------------------------------------------------------

@dataclass
class Elf:
    """The loadable image of a 32-bit little-endian RISC-V ELF executable."""

    entry: int
    segments: list[tuple[int, bytes]]  # (physical address, bytes incl. zero fill)
    symbols: dict[str, int]


def read_elf(path: str | Path) -> Elf:
    """Parse PT_LOAD segments and the symbol table (ELF32 little-endian only)."""
    data = Path(path).read_bytes()
    if data[:4] != b"\x7fELF" or data[4] != 1 or data[5] != 1:
        raise ValueError(f"{path}: not an ELF32 little-endian file")
    (e_type, e_machine, _ver, entry, phoff, shoff, _flags, _ehsize, phentsize, phnum,
     shentsize, shnum, _shstrndx) = struct.unpack_from("<HHIIIIIHHHHHH", data, 16)
    if e_machine != 243:
        raise ValueError(f"{path}: not a RISC-V ELF (e_machine {e_machine})")
    segments = []
    for i in range(phnum):
        p_type, p_offset, _vaddr, p_paddr, p_filesz, p_memsz, _fl, _al = struct.unpack_from(
            "<IIIIIIII", data, phoff + i * phentsize)
        if p_type == 1 and p_memsz:
            blob = data[p_offset:p_offset + p_filesz] + bytes(p_memsz - p_filesz)
            segments.append((p_paddr, blob))
    symbols: dict[str, int] = {}
    sections = [struct.unpack_from("<IIIIIIIIII", data, shoff + i * shentsize) for i in range(shnum)]
    for sh in sections:
        if sh[1] == 2:  # SHT_SYMTAB
            strtab = sections[sh[6]]
            for j in range(sh[5] // 16):
                st_name, st_value, _size, _info, _other, _shndx = struct.unpack_from(
                    "<IIIBBH", data, sh[4] + j * 16)
                start = strtab[4] + st_name
                name = data[start:data.index(b"\0", start)].decode()
                if name:
                    symbols[name] = st_value
    return Elf(entry, segments, symbols)


def load_elf(mem: Memory, elf: Elf) -> None:
    for addr, blob in elf.segments:
        mem.write_bytes(addr, blob)


def run_to_tohost(sim: Rv32, tohost: int, max_steps: int) -> tuple[int, int]:
    """Step until a non-zero word is stored to ``tohost``; return (value, retired
    instructions), not counting steps that took a trap."""
    retired = 0
    for _ in range(max_steps):
        sim.step()
        if sim.last_trap is None:
            retired += 1
        st = sim.last_store
        if st is not None and st[0] == tohost and st[2] != 0:
            return st[2], retired
    raise TimeoutError(f"no tohost write within {max_steps} steps (pc {sim.pc:#x})")


@dataclass
class IssResult:
    tohost: int
    instructions: int
    signature: list[int]


def signature_words(mem: Memory, symbols: dict[str, int]) -> list[int]:
    """The words from ``begin_signature`` to ``end_signature``."""
    begin, end = symbols["begin_signature"], symbols["end_signature"]
    return [mem.load(a, 4) or 0 for a in range(begin, end, 4)]


def run_iss(elf_path: str | Path, ram_base: int, ram_bytes: int, max_steps: int = 5_000_000) -> IssResult:
    """Run an ELF from its entry point, with RAM at ``ram_base``, until tohost is written."""
    elf = read_elf(elf_path)
    mem = Memory()
    mem.add_ram(ram_base, ram_bytes)
    load_elf(mem, elf)
    sim = Rv32(mem, pc=elf.entry)
    value, steps = run_to_tohost(sim, elf.symbols["tohost"], max_steps)
    return IssResult(value, steps, signature_words(mem, elf.symbols))
