/* SPDX-License-Identifier: MIT */
/* The loop over every pair of operand words of the M-extension test programs
 * (muldiv_corners.S, div_widths.S): PAIRS_BEGIN n loads a = operands[i] into
 * x4 and b = operands[j] into x5 for i, j in 0..n-1 (x31 walks the results),
 * the program's body stores what it computes at 0(x31) on, PAIRS_END stride
 * moves x31 on by stride bytes, closes both loops and reports 1 to tohost;
 * PAIRS_RESULTS n, stride after the program's `operands` reserves the
 * signature (n * n * stride bytes) and places tohost.
 * Registers x1-x3 and x29-x31 are the loop's; the labels `operands`,
 * `results` and `tohost` are the program's. */
.macro PAIRS_BEGIN n
    la      x31, results
    la      x30, operands
    li      x29, \n             /* operand count */
    li      x1, 0               /* i */
1:  li      x2, 0               /* j */
2:  slli    x3, x1, 2
    add     x3, x3, x30
    lw      x4, 0(x3)           /* a */
    slli    x3, x2, 2
    add     x3, x3, x30
    lw      x5, 0(x3)           /* b */
.endm

.macro PAIRS_END stride
    addi    x31, x31, \stride
    addi    x2, x2, 1
    blt     x2, x29, 2b
    addi    x1, x1, 1
    blt     x1, x29, 1b
    li      x1, 1
    la      x2, tohost
    sw      x1, 0(x2)
3:  j       3b
.endm

.macro PAIRS_RESULTS n, stride
    .section .signature, "aw", @progbits
results: .zero \n * \n * \stride

    .section .tohost, "aw", @progbits
    .align  6
    .globl  tohost
tohost: .word 0
.endm
