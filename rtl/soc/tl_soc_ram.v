// SPDX-License-Identifier: MIT
// tl_soc_ram: program/data RAM, true dual-port block RAM initialised from a hex file.
//
// Port A serves the CPU data bus (read/write with byte enables), port B the
// instruction bus (read only), so a fetch never waits for a load/store.
// Intel template: "True Dual-Port RAM with single clock" (Quartus Prime
// Recommended HDL Coding Styles, True Dual-Port Synchronous RAM, Verilog),
// which Quartus maps to M10K blocks in true dual-port mode: one always block
// per port, registered read data, and no promise for a read during a write:
// port A reads only when it does not write (a read enable; the fabric never
// uses read data of a store, so no same-port read-during-write mode is
// needed, "old data" being one the M10K lacks), and a fetch of a word the
// data port writes in the same cycle is undefined on the FPGA (the
// simulators return the old word).  Byte enables are the write expressions
// with two indexes of the template "RAM with Byte-Enable Signals", one per
// byte lane.
// $readmemh in an initial block initialises the blocks in the bitstream
// ("Specifying Initial Memory Contents at Power-Up").  No reset: block RAM
// contents survive reset.  tl_soc_fabric writes only on an access it
// launches and acknowledges every access itself.
`default_nettype none

module tl_soc_ram #(
    parameter integer RAM_BYTES = 65536,          // power of two; 64 KiB = 64 M10K
    parameter         INIT_FILE = "",             // $readmemh image, one 32-bit word per line
    parameter integer ADDR_BITS = $clog2(RAM_BYTES)
) (
    input  wire        clk,
    // port A: data bus
    input  wire        a_we,                     // write strobe (the fabric's launch of a store)
    input  wire [3:0]  a_be,
    /* verilator lint_off UNUSEDSIGNAL */  // addr[1:0]: byte lanes come from be
    input  wire [ADDR_BITS-1:0] a_addr,           // byte address inside the RAM
    /* verilator lint_on UNUSEDSIGNAL */
    input  wire [31:0] a_wdata,
    output reg  [31:0] a_rdata,
    // port B: instruction bus
    /* verilator lint_off UNUSEDSIGNAL */
    input  wire [ADDR_BITS-1:0] b_addr,
    /* verilator lint_on UNUSEDSIGNAL */
    output reg  [31:0] b_rdata
);

    localparam integer WORDS = RAM_BYTES / 4;

    reg [31:0] mem [0:WORDS-1];

    initial begin
        if (INIT_FILE != "")
            $readmemh(INIT_FILE, mem);
    end

    wire [ADDR_BITS-3:0] a_idx = a_addr[ADDR_BITS-1:2];
    wire [ADDR_BITS-3:0] b_idx = b_addr[ADDR_BITS-1:2];

    always @(posedge clk) begin        // port A
        if (a_we) begin
            if (a_be[0]) mem[a_idx][7:0]   <= a_wdata[7:0];
            if (a_be[1]) mem[a_idx][15:8]  <= a_wdata[15:8];
            if (a_be[2]) mem[a_idx][23:16] <= a_wdata[23:16];
            if (a_be[3]) mem[a_idx][31:24] <= a_wdata[31:24];
        end else begin
            a_rdata <= mem[a_idx];
        end
    end

    always @(posedge clk) begin        // port B: the template's port with its write enable tied low
        b_rdata <= mem[b_idx];
    end

endmodule

`default_nettype wire
