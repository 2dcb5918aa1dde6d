/* SPDX-License-Identifier: MIT */
/* Start-up of every torqueloop firmware image (firmware/common/link.ld):
   the image is loaded into RAM (RAM_INIT, or by a bootloader), so no .data
   copy is needed; set gp and sp, clear .bss, call main, spin if it returns.
   The image header after the first jump (magic, register-map version; values
   from the linker script) marks it as firmware for this board: `torqueloop
   upload --raw` refuses a binary without it. */
    .section .text.start, "ax"
    .globl _start
_start:
    j    0f
    .word __tl_image_magic
    .word __tl_image_map_version
0:
    .option push
    .option norelax
    la   gp, __global_pointer$
    .option pop
    la   sp, __stack_top
    la   t0, __bss_start
    la   t1, __bss_end
1:  bgeu t0, t1, 2f
    sw   zero, 0(t0)
    addi t0, t0, 4
    j    1b
2:  call main
3:  j    3b
