/* SPDX-License-Identifier: MIT */
# The divider's early exits: DIV, DIVU, REM and REMU on every pair of operands
# of bit widths around its skip thresholds (1-3, 7-9, 15-17, 23-25, 31, 32 bits;
# each width's largest and smallest value, as signed operands also negative
# where bit 31 is set), results in the signature.  tl_cpu_pipe's divider skips
# 8 leading quotient bits when the dividend's top byte is below the divisor
# (a skip of 16, for its high half, was tried too): these pairs sit on both
# sides of each threshold.
#include "pair_loop.h"
    .section .text.init, "ax"
    .globl _start
_start:
    PAIRS_BEGIN 28
    div     x6, x4, x5
    sw      x6, 0(x31)
    divu    x6, x4, x5
    sw      x6, 4(x31)
    rem     x6, x4, x5
    sw      x6, 8(x31)
    remu    x6, x4, x5
    sw      x6, 12(x31)
    PAIRS_END 16

    .section .data
operands:
    .word   0x00000001, 0x00000001, 0x00000003, 0x00000002, 0x00000007, 0x00000004, 0x0000007f, 0x00000040, 0x000000ff, 0x00000080, 0x000001ff, 0x00000100, 0x00007fff, 0x00004000, 0x0000ffff, 0x00008000, 0x0001ffff, 0x00010000, 0x007fffff, 0x00400000, 0x00ffffff, 0x00800000, 0x01ffffff, 0x01000000, 0x7fffffff, 0x40000000, 0xffffffff, 0x80000000

    PAIRS_RESULTS 28, 16
