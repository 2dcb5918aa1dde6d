// SPDX-License-Identifier: MIT
// mcause exception codes of the machine-mode traps the cores raise
// (RISC-V privileged spec, table "Machine cause register values"; the
// interrupt codes come from tl_cpu_csr's priority decision).  Included inside
// the module body of tl_cpu and tl_cpu_pipe: localparams, no macros.
localparam [3:0] CAUSE_FETCH_MISALIGNED = 4'd0;
localparam [3:0] CAUSE_FETCH_FAULT      = 4'd1;
localparam [3:0] CAUSE_ILLEGAL          = 4'd2;
localparam [3:0] CAUSE_BREAKPOINT       = 4'd3;
localparam [3:0] CAUSE_LOAD_MISALIGNED  = 4'd4;
localparam [3:0] CAUSE_LOAD_FAULT       = 4'd5;
localparam [3:0] CAUSE_STORE_MISALIGNED = 4'd6;
localparam [3:0] CAUSE_STORE_FAULT      = 4'd7;
localparam [3:0] CAUSE_ECALL_M          = 4'd11;
