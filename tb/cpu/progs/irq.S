/* SPDX-License-Identifier: MIT */
# Interrupts on cpu_sim_top, through the SoC's own timer and interrupt
# controller at their SoC addresses (firmware/include/torqueloop_regs.h):
# TIMER.MTIMECMP raises irq_timer, TIMER.MSIP irq_software, INTC.SET with
# the source enabled raises irq_external (W1C INTC.PENDING drops it).
# Self-checking: tohost = 1 on success, else (n << 1) | 1 with n the failed
# check.  Every trap's mcause is appended to `log` (in the signature), which
# the test bench compares with the expected sequence; it also measures
# latency on the timer interrupts.
#   1. timer interrupt taken from a spin loop, 4 times
#   2. masking: pending but MIE = 0 or MTIE = 0 -> not taken; enabling
#      takes it right after the enabling instruction
#   3. nesting: the timer handler re-enables MIE and raises the external
#      interrupt, which preempts it
#   4. priority: external > software > timer when all are pending
#   5. timer interrupts landing in divides: the results stay right
#   6. (first, before any interrupt) the time CSR follows mtime, and mcycle
#      counts clock cycles like mtime does
#include "torqueloop_regs.h"
    # s0 = TIMER page, s1 = INTC page
    .equ    MTIME,    TL_TIMER_MTIME_LO_OFS
    .equ    CMP_LO,   TL_TIMER_MTIMECMP_LO_OFS
    .equ    CMP_HI,   TL_TIMER_MTIMECMP_HI_OFS
    .equ    MSIP,     TL_TIMER_MSIP_OFS
    .equ    PENDING,  TL_INTC_PENDING_OFS
    .equ    ENABLE,   TL_INTC_ENABLE_OFS
    .equ    SET,      TL_INTC_SET_OFS
    # Any INTC source will do: the harness wires none, the program sets it.
    .equ    EXT,      TL_INTC_PENDING_GPIO_KEY_MSK

    .macro  fail n
    li      a0, \n
    j       report
    .endm

    .section .text.init, "ax"
    .globl _start
_start:
    la      sp, __stack_top
    la      x27, log
    li      x20, 0              # timer interrupts taken
    li      x22, 0              # external interrupts taken
    li      x24, 0              # 1: timer handler nests an external interrupt
    li      x25, 0              # software interrupts taken
    li      s0, TL_TIMER_BASE
    li      s1, TL_INTC_BASE
    li      t0, EXT
    sw      t0, ENABLE(s1)      # the external source enabled; it stays idle until SET
    la      t0, handler
    csrw    mtvec, t0

    # --- 6. counters ---
    csrr    t0, time
    lw      t1, MTIME(s0)
    sub     t1, t1, t0          # mtime read a few cycles after time
    bltz    t1, 30f
    li      t2, 8
    bge     t1, t2, 30f
    csrr    a1, mcycle
    lw      a2, MTIME(s0)
    li      t1, 100
31: addi    t1, t1, -1
    bnez    t1, 31b
    csrr    a3, mcycle
    lw      a4, MTIME(s0)
    sub     a1, a3, a1
    sub     a2, a4, a2
    sub     a1, a1, a2          # same cycle count over the loop
    bnez    a1, 32f
    rdcycle a3
    csrr    a4, mcycle
    csrr    a5, cycle
    sub     a3, a4, a3
    sub     a4, a5, a4
    beqz    a3, 32f             # one counter behind cycle and mcycle, counting:
    bne     a3, a4, 32f         # the same steps between back-to-back reads
    j       33f
30: fail    11
32: fail    12
33:
    li      t0, 0x888           # MEIE | MTIE | MSIE
    csrw    mie, t0
    csrsi   mstatus, 8

    # --- 1. timer from a spin loop, 4 times ---
    li      s2, 4
1:  mv      s3, x20
    lw      t0, MTIME(s0)
    addi    t0, t0, 100
    sw      t0, CMP_LO(s0)      # mtimecmp lo (hi is still all ones)
    sw      zero, CMP_HI(s0)    # mtimecmp hi = 0: armed
    li      t1, 10000
2:  addi    t1, t1, -1
    beqz    t1, 3f
    beq     s3, x20, 2b
    addi    s2, s2, -1
    bnez    s2, 1b
    j       4f
3:  fail    1

    # --- 2. masking ---
4:  csrci   mstatus, 8          # MIE = 0
    mv      s3, x20
    sw      zero, CMP_LO(s0)
    sw      zero, CMP_HI(s0)    # mtimecmp = 0: pending now
    csrr    t0, mip
    andi    t0, t0, 0x80
    bnez    t0, 5f
    fail    2
5:  li      t1, 50
6:  addi    t1, t1, -1
    bnez    t1, 6b
    bne     s3, x20, 7f
    li      t0, 0x80
    csrc    mie, t0             # MTIE = 0 ...
    csrsi   mstatus, 8          # ... and MIE = 1: still masked
    nop
    nop
    bne     s3, x20, 7f
    li      t0, 0x80
    csrs    mie, t0             # taken right after this instruction
    addi    s3, s3, 1
    bne     s3, x20, 8f
    j       9f
7:  fail    3
8:  fail    4

    # --- 3. nesting ---
9:  li      x24, 1
    mv      s3, x22
    lw      t0, MTIME(s0)
    addi    t0, t0, 20
    sw      t0, CMP_LO(s0)
    sw      zero, CMP_HI(s0)
    li      t1, 10000
10: addi    t1, t1, -1
    beqz    t1, 11f
    beq     s3, x22, 10b
    li      x24, 0
    addi    s3, s3, 1
    bne     x23, s3, 12f        # the timer handler saw the nested external one
    j       13f
11: fail    5
12: fail    6

    # --- 4. priority: all three pending, then enable ---
13: csrci   mstatus, 8
    li      t0, EXT
    sw      t0, SET(s1)         # external line high
    li      t0, 1
    sw      t0, MSIP(s0)        # software line high
    sw      zero, CMP_LO(s0)
    sw      zero, CMP_HI(s0)    # timer pending
    csrsi   mstatus, 8          # taken in priority order: MEI, MSI, MTI
    nop
    li      t0, 1
    bne     x25, t0, 14f
    j       15f
14: fail    7

    # --- 5. timer interrupts during divides ---
    # (a6/a7, not s4 = x20 and s6 = x22: the handlers count in x20 and x22)
15: li      s2, 60              # iterations
    li      a6, 0x9e3779b9      # operand generator state
    li      s5, 3               # timer offset, walks 3..
    mv      a7, x20
16: lw      t0, MTIME(s0)
    add     t0, t0, s5
    sw      t0, CMP_LO(s0)
    sw      zero, CMP_HI(s0)
    li      t0, 1664525
    mul     a6, a6, t0
    li      t0, 1013904223
    add     a6, a6, t0          # a
    srai    s7, a6, 9
    ori     s7, s7, 1           # b != 0
    div     t2, a6, s7
    rem     t3, a6, s7
    mul     t4, t2, s7
    add     t4, t4, t3
    bne     t4, a6, 17f         # q * b + r == a
    divu    t2, a6, s7
    remu    t3, a6, s7
    mul     t4, t2, s7
    add     t4, t4, t3
    bne     t4, a6, 17f
    bgeu    t3, s7, 17f         # unsigned remainder < divisor
    mv      t5, a6
    divu    t5, t5, s7          # rd = rs1: an abandoned divide must not have written it
    bne     t5, t2, 17f
    mv      t6, s7
    mul     t6, t6, t2          # rd = rs1 for an abandoned multiply too
    mul     t4, s7, t2
    beq     t6, t4, 18f
17: fail    8
18: addi    s5, s5, 1
    li      t0, 40
    blt     s5, t0, 19f
    li      s5, 3
19: addi    s2, s2, -1
    bnez    s2, 16b
    li      t0, -1
    sw      t0, CMP_HI(s0)      # disarm
    sub     t0, x20, a7
    li      t1, 30
    bge     t0, t1, 20f         # most iterations took a timer interrupt
    fail    9
20: li      a0, 0

report:
    csrci   mstatus, 8
    la      t1, log_count
    la      t2, log
    sub     t0, x27, t2
    srli    t0, t0, 2
    sw      t0, 0(t1)
    slli    a0, a0, 1
    ori     a0, a0, 1
    la      t0, tohost
    sw      a0, 0(t0)
21: j       21b

    .align  2
    .globl  handler
handler:
    addi    sp, sp, -16
    sw      x28, 0(sp)
    sw      x29, 4(sp)
    csrr    x28, mepc
    sw      x28, 8(sp)
    csrr    x28, mstatus
    sw      x28, 12(sp)
    csrr    x29, mcause
    sw      x29, 0(x27)
    addi    x27, x27, 4
    li      x28, 0x80000007
    beq     x29, x28, h_timer
    li      x28, 0x8000000b
    beq     x29, x28, h_ext
    li      x28, 0x80000003
    beq     x29, x28, h_sw
    li      a0, 10              # unexpected trap
    j       report
h_timer:
    li      x28, -1
    sw      x28, CMP_HI(s0)     # mtimecmp hi = all ones: line low
    addi    x20, x20, 1
    beqz    x24, h_done
    csrsi   mstatus, 8          # allow nesting
    li      x28, EXT
    sw      x28, SET(s1)        # raise external: preempts this handler now
    nop
    mv      x23, x22
    csrci   mstatus, 8
    j       h_done
h_ext:
    li      x28, EXT
    sw      x28, PENDING(s1)    # drop the external line (W1C), keep software
    addi    x22, x22, 1
    j       h_done
h_sw:
    sw      zero, MSIP(s0)
    addi    x25, x25, 1
h_done:
    lw      x28, 12(sp)
    csrw    mstatus, x28
    lw      x28, 8(sp)
    csrw    mepc, x28
    lw      x28, 0(sp)
    lw      x29, 4(sp)
    addi    sp, sp, 16
    mret

    .section .signature, "aw", @progbits
log_count: .word 0
log:    .zero 4 * 128

    .section .tohost, "aw", @progbits
    .align  6
    .globl  tohost
tohost: .word 0
    .word   0
