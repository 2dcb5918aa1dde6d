// SPDX-License-Identifier: MIT
// tl_soc_rom: boot ROM (reset vector at 0), block RAM without a write port,
// initialised from a hex file, readable by both buses in the same cycle.
// Intel template: "Dual-Port Synchronous ROM Using readmemb" (Quartus Prime
// Recommended HDL Coding Styles, Inferring ROM Functions from HDL Code),
// with $readmemh: both reads registered in one always block, contents from
// an initial block, which Quartus maps to M10K in ROM mode.
// tl_soc_fabric acknowledges every access and answers a data-bus write with a
// bus error (the CPU raises a store access fault) rather than dropping it
// silently: writing the ROM is always a bug.
`default_nettype none

module tl_soc_rom #(
    parameter integer ROM_BYTES = 4096,
    parameter         INIT_FILE = "",
    parameter integer ADDR_BITS = $clog2(ROM_BYTES)
) (
    input  wire        clk,
    // port A: data bus (reads only)
    /* verilator lint_off UNUSEDSIGNAL */  // addr[1:0]: byte lanes come from be
    input  wire [ADDR_BITS-1:0] a_addr,
    /* verilator lint_on UNUSEDSIGNAL */
    output reg  [31:0] a_rdata,
    // port B: instruction bus
    /* verilator lint_off UNUSEDSIGNAL */
    input  wire [ADDR_BITS-1:0] b_addr,
    /* verilator lint_on UNUSEDSIGNAL */
    output reg  [31:0] b_rdata
);

    localparam integer WORDS = ROM_BYTES / 4;

    reg [31:0] mem [0:WORDS-1];

    initial begin
        if (INIT_FILE != "")
            $readmemh(INIT_FILE, mem);
    end

    always @(posedge clk) begin
        a_rdata <= mem[a_addr[ADDR_BITS-1:2]];
        b_rdata <= mem[b_addr[ADDR_BITS-1:2]];
    end

endmodule

`default_nettype wire
