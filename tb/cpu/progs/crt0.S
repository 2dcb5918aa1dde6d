/* SPDX-License-Identifier: MIT */
# Start-up of the C test programs: stack at the top of RAM, call main,
# report through tohost: 1 if main returned 0, else (main << 1) | 1
# (riscv-tests convention: the failing check's number).
    .section .text.init, "ax"
    .globl _start
_start:
    la      sp, __stack_top
    call    main
    slli    a0, a0, 1
    ori     a0, a0, 1
    la      t0, tohost
    sw      a0, 0(t0)
1:  j       1b

    .section .tohost, "aw", @progbits
    .align  6
    .globl  tohost
tohost: .word 0
    .word   0
