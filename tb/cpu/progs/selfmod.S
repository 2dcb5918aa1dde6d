/* SPDX-License-Identifier: MIT */
# Code rewritten by stores runs as rewritten: a loop's backward branch and a
# jal, each run until the pipelined core's branch target buffer holds them,
# are overwritten (a word store, then byte and halfword stores) and run
# again.  The core drops a BTB entry when a store to its word retires, and
# every entry on fence.i; the ISS runs the memory as it is.  Pass 2 has no
# fence.i (the core sees a store in every fetch issued after the store
# retired: the nops keep the rewritten words out of the prefetch queue);
# pass 3 has one.  The sum of each pass goes into the signature.
# one pass: the kernel run twice from a zero sum, the sum stored at results + off
    .macro run_pass off
    li      x10, 0
    jal     ra, kernel
    jal     ra, kernel
    sw      x10, \off(x31)
    .endm
# four nops: keep the rewritten words out of the prefetch queue
    .macro nops4
    nop
    nop
    nop
    nop
    .endm
    .section .text.init, "ax"
    .globl _start
_start:
    la      x31, results
    la      x20, patch_br
    la      x21, patch_j
    lw      x22, 0(x20)         # the original words, to restore them in pass 3
    lw      x23, 0(x21)
    li      x24, 0x00000013     # nop
    # pass 1: as assembled (5 loop turns, then the jal to k_a), twice
    run_pass 0
    # pass 2: the branch and the jal become nops (one turn, then k_b)
    sw      x24, 0(x20)
    sw      x24, 0(x21)
    nops4
    run_pass 4
    # pass 3: the branch restored byte by byte, the jal by halves, then fence.i
    mv      x5, x22
    sb      x5, 0(x20)
    srli    x5, x5, 8
    sb      x5, 1(x20)
    srli    x5, x5, 8
    sb      x5, 2(x20)
    srli    x5, x5, 8
    sb      x5, 3(x20)
    sh      x23, 0(x21)
    srli    x5, x23, 16
    sh      x5, 2(x21)
    .word   0x0000100f          # fence.i (Zifencei not in -march)
    run_pass 8
    # pass 4: the branch a nop again, by one halfword (its low half), no fence.i
    sh      x24, 0(x20)
    srli    x5, x24, 16
    sh      x5, 2(x20)
    nops4
    run_pass 12
    li      x1, 1
    la      x2, tohost
    sw      x1, 0(x2)
1:  j       1b

    .align  4
kernel:
    li      x11, 5
1:  addi    x10, x10, 1
    addi    x11, x11, -1
patch_br:
    bnez    x11, 1b
patch_j:
    j       k_a
k_b:
    addi    x10, x10, 100
    ret
k_a:
    addi    x10, x10, 1000
    ret

    .section .signature, "aw", @progbits
results: .zero 16

    .section .tohost, "aw", @progbits
    .align  6
    .globl  tohost
tohost: .word 0
    .word   0
