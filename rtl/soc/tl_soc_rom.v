// SPDX-License-Identifier: MIT
// soc_rom: boot ROM (reset vector at 0), block RAM without a write port,
// initialised from a hex file, readable by both buses in the same cycle.
//
// A data-bus write answers with a bus error (the CPU raises a store access
// fault) rather than being silently dropped: writing the ROM is always a bug.
// Slave contract as in soc_ram.v.
`default_nettype none

module tl_soc_rom #(
    parameter integer ROM_BYTES = 4096,
    parameter         INIT_FILE = "",
    parameter integer ADDR_BITS = $clog2(ROM_BYTES)
) (
    input  wire        clk,
    input  wire        rst,
    // port A: data bus (reads only; writes -> err)
    input  wire        a_req,
    input  wire        a_we,
    /* verilator lint_off UNUSEDSIGNAL */  // addr[1:0]: byte lanes come from be
    input  wire [ADDR_BITS-1:0] a_addr,
    /* verilator lint_on UNUSEDSIGNAL */
    output reg         a_ack,
    output reg         a_err,
    output reg  [31:0] a_rdata,
    // port B: instruction bus
    input  wire        b_req,
    /* verilator lint_off UNUSEDSIGNAL */
    input  wire [ADDR_BITS-1:0] b_addr,
    /* verilator lint_on UNUSEDSIGNAL */
    output reg         b_ack,
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

    always @(posedge clk) begin
        if (rst) begin
            a_ack <= 1'b0;
            a_err <= 1'b0;
            b_ack <= 1'b0;
        end else begin
            a_ack <= a_req;
            a_err <= a_req && a_we;
            b_ack <= b_req;
        end
    end

endmodule

`default_nettype wire
