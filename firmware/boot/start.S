/* SPDX-License-Identifier: MIT */
/* Boot ROM entry, at the reset vector (RESET_PC = TL_BOOT_ROM_BASE).  Also the
 * bootloader's entry from firmware (docs/bootloader.md, 'Entry convention'):
 * nothing is assumed about registers, CSRs or RAM.  Interrupts go off first;
 * a trap while the bootloader runs restarts it (mtvec = _start) rather than
 * landing in a handler of the firmware that jumped here. */
    .section .text.start, "ax"
    .globl _start
    .p2align 2
_start:
    csrw mstatus, zero
    csrw mie, zero
    la   t0, _start
    csrw mtvec, t0
    la   sp, __boot_stack_top
    call boot_main
1:  j    1b
