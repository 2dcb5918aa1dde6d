/* SPDX-License-Identifier: MIT */
// Never writes tohost: run_elf.py must stop at --max-cycles.
int main(void) {
    for (;;)
        __asm__ volatile("");
}
