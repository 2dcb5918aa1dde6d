/* SPDX-License-Identifier: MIT */
# Every M-extension operation on every pair of corner operands
# (0, 1, -1, 2, -2, 2^31-1, -2^31, 0x55555555, 0xAAAAAAAB, 7, -7), results
# in the signature: division by zero, -2^31 / -1 and the MULH sign cases.
#include "pair_loop.h"
    .section .text.init, "ax"
    .globl _start
_start:
    PAIRS_BEGIN 11
    mul     x6, x4, x5
    sw      x6, 0(x31)
    mulh    x6, x4, x5
    sw      x6, 4(x31)
    mulhsu  x6, x4, x5
    sw      x6, 8(x31)
    mulhu   x6, x4, x5
    sw      x6, 12(x31)
    div     x6, x4, x5
    sw      x6, 16(x31)
    divu    x6, x4, x5
    sw      x6, 20(x31)
    rem     x6, x4, x5
    sw      x6, 24(x31)
    remu    x6, x4, x5
    sw      x6, 28(x31)
    mul     x0, x4, x5          # rd = x0 stays zero
    div     x0, x4, x5
    sw      x0, 32(x31)
    div     x4, x4, x5          # rd = rs1
    sw      x4, 36(x31)
    PAIRS_END 40

    .section .data
operands:
    .word   0, 1, -1, 2, -2, 0x7fffffff, 0x80000000, 0x55555555, 0xaaaaaaab, 7, -7

    PAIRS_RESULTS 11, 40
