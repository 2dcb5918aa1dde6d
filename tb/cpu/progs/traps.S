/* SPDX-License-Identifier: MIT */
# Exceptions, CSRs and mret, compared word for word with the ISS.
# The handler logs (mcause, mepc - _start, mtval, mstatus) of every trap into
# the signature and resumes after the faulting instruction (or at ra for an
# instruction-fetch fault).  x28..x31 belong to the handler.
    .section .text.init, "ax"
    .globl _start
_start:
    # registers are not reset: give each a known value first
    .irp    r, 1,2,3,4,5,6,7,8,9,10,11,12,13,14,15,16,17,18,19,20,21,22,23,24,25,26,27
    li      x\r, (\r * 0x01000193)
    .endr
    la      x31, log            # trap log pointer
    la      x1, handler
    csrw    mtvec, x1
    la      x20, data

    # --- illegal instructions ---
    .word   0x00000000          # all zeros
    .word   0xffffffff          # all ones
    .word   0x00004073          # SYSTEM funct3 = 100
    .word   0x02005013          # srli with funct7 = 1
    .word   0x4000100b          # custom-0 opcode
    .word   0x00002067          # jalr with funct3 = 010
    .word   0x00006003          # load funct3 = 110 (LWU is RV64 only)
    .word   0x00003023          # store funct3 = 011 (SD is RV64 only)
    .word   0x00002063          # branch funct3 = 010
    .word   0x40001033          # sll with funct7 = 0100000
    .word   0x10200073          # sret: no S-mode
    csrr    x2, 0x7c0           # unknown CSR
    csrw    mhartid, x1         # write to a read-only CSR
    csrrs   x3, mvendorid, x1   # set with rs1 != 0 on a read-only CSR
    csrrs   x4, mhartid, x0     # legal: no write
    csrrci  x5, marchid, 0      # legal: no write

    # --- ecall, ebreak ---
    ecall
    ebreak

    # --- misaligned loads and stores (mtval = address) ---
    lw      x6, 1(x20)
    lw      x6, 2(x20)
    lh      x7, 1(x20)
    lhu     x7, 3(x20)
    lb      x8, 3(x20)          # legal
    lbu     x9, 1(x20)          # legal
    lh      x10, 2(x20)         # legal
    sw      x1, 3(x20)
    sh      x1, 1(x20)
    sb      x1, 1(x20)          # legal

    # --- misaligned jump targets: rd must not be written ---
    li      x11, 0x1234
    la      x12, 1f
    addi    x12, x12, 2
    jalr    x11, 0(x12)
1:  .word   0x00000163          # beq x0, x0, +2: taken, misaligned
    .word   0x00001163          # bne x0, x0, +2: not taken, no trap
    la      x12, 2f
    jalr    x13, 1(x12)         # bit 0 is cleared: aligned, no trap
    nop
2:  nop

    # --- access faults (nothing mapped at 0x1000_0000) ---
    li      x14, 0x10000000
    lw      x15, 0(x14)
    sw      x15, 4(x14)
    lb      x15, 7(x14)
    jalr    ra, 0(x14)          # fetch fault: the handler returns to ra

    # --- fetch fault on the word after the last one in RAM, reached after
    #     a load and after a divide (the core prefetches during those) ---
    li      x14, 0x8000fffc
    la      x15, tail_insns
    lw      x16, 0(x15)         # "lw x16, 4(x20)"
    sw      x16, 0(x14)
    .word   0x0000100f          # fence.i
    jalr    ra, 0(x14)
    lw      x16, 4(x15)         # "div x16, x16, x21"
    sw      x16, 0(x14)
    .word   0x0000100f
    jalr    ra, 0(x14)

    # --- mstatus across a trap: MIE -> MPIE, mret restores ---
    csrsi   mstatus, 8          # MIE = 1 (mie = 0: no interrupt can fire)
    ecall
    csrr    x16, mstatus
    csrci   mstatus, 8
    csrr    x17, mstatus

    # --- vectored mtvec: exceptions still go to BASE ---
    la      x1, handler
    ori     x1, x1, 1
    csrw    mtvec, x1
    ecall
    csrr    x18, mtvec
    li      x1, -1
    csrw    mtvec, x1           # MODE 3 is reserved: reads back as 1
    csrr    x19, mtvec
    la      x1, handler
    csrw    mtvec, x1

    # --- CSR read/modify/write forms ---
    li      x1, 0x5a5aa5a5
    csrrw   x21, mscratch, x1
    csrrsi  x21, mscratch, 0x1f
    csrrci  x22, mscratch, 0x15
    li      x1, 0xff00
    csrrc   x23, mscratch, x1
    csrrs   x24, mscratch, x0
    csrrwi  x25, mscratch, 7
    csrr    x26, mscratch
    li      x1, -1
    csrw    mie, x1             # only MSIE, MTIE, MEIE stick
    csrr    x27, mie
    csrw    mie, x0
    csrw    mepc, x1            # low bits read as 0
    csrr    x1, mepc
    sw      x1, 0(x31)
    csrr    x1, misa
    sw      x1, 4(x31)
    csrr    x1, mhartid
    sw      x1, 8(x31)
    csrw    mcause, x20
    csrr    x1, mcause
    sw      x1, 12(x31)
    csrw    mtval, x20
    csrr    x1, mtval
    sw      x1, 16(x31)
    csrr    x1, mip             # no interrupt lines high
    sw      x1, 20(x31)
    csrw    minstret, x0        # the write replaces this instruction's count
    nop
    nop
    csrr    x1, minstret
    sw      x1, 24(x31)
    csrr    x1, instret         # user shadow
    sw      x1, 28(x31)
    csrr    x1, minstreth
    sw      x1, 32(x31)
    fence
    .word   0x0000100f          # fence.i (Zifencei not in -march): a no-op here
    wfi
    addi    x31, x31, 36

    # dump x1..x27
    la      x30, regs
    .irp    r, 1,2,3,4,5,6,7,8,9,10,11,12,13,14,15,16,17,18,19,20,21,22,23,24,25,26,27
    sw      x\r, (\r * 4)(x30)
    .endr
    la      x1, log_end
    sub     x1, x1, x31          # log space left (must be >= 0)
    bltz    x1, 3f
    li      x1, 1
    j       4f
3:  li      x1, 3
4:  la      x2, tohost
    sw      x1, 0(x2)
5:  j       5b

tail_insns:
    lw      x16, 4(x20)
    div     x16, x16, x21

    .align  2
handler:
    csrr    x28, mcause
    sw      x28, 0(x31)
    csrr    x29, mepc
    la      x30, _start
    sub     x30, x29, x30
    sw      x30, 4(x31)
    csrr    x30, mtval
    sw      x30, 8(x31)
    csrr    x30, mstatus
    sw      x30, 12(x31)
    addi    x31, x31, 16
    li      x30, 1
    bne     x28, x30, 6f
    csrw    mepc, ra            # fetch fault: back to the caller
    mret
6:  addi    x29, x29, 4
    csrw    mepc, x29
    mret

    .section .data
data:   .word 0x89abcdef, 0x01234567

    .section .signature, "aw", @progbits
log:    .zero 16 * 48
log_end:
        .zero 64
regs:   .zero 128

    .section .tohost, "aw", @progbits
    .align  6
    .globl  tohost
tohost: .word 0
    .word   0
