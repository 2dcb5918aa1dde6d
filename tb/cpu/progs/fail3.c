/* SPDX-License-Identifier: MIT */
// Reports failed test 3 through tohost: run_elf.py must exit non-zero.
int main(void) { return 3; }
