// SPDX-License-Identifier: MIT
// tl_sync_fifo: single-clock first-word-fall-through FIFO with valid/ready on
// both sides (the UART's RX and TX buffers).
//
// DEPTH entries (a power of two); the pointers carry one extra bit so that
// full and empty differ without a separate flag, and `level` (entries held)
// is their difference.  The read port is asynchronous (m_data shows the
// oldest entry whenever m_valid is high).  Intel template: none for block
// RAM - a memory with an asynchronous read goes to MLAB or registers
// (Quartus Prime Recommended HDL Coding Styles, "Use Synchronous Memory
// Blocks"), fine at 16 x 8; depths that want an M10K would need a
// registered read.
// A write while full is refused (s_ready low), never overwrites.
`default_nettype none

module tl_sync_fifo #(
    parameter integer WIDTH = 8,
    parameter integer DEPTH = 16     // power of two, >= 2
) (
    input  wire                     clk,
    input  wire                     rst,      // synchronous, active high: empties the FIFO
    input  wire [WIDTH-1:0]         s_data,
    input  wire                     s_valid,
    output wire                     s_ready,
    output wire [WIDTH-1:0]         m_data,
    output wire                     m_valid,
    input  wire                     m_ready,
    output wire [$clog2(DEPTH):0]   level
);

    localparam integer AW = $clog2(DEPTH);

    reg [WIDTH-1:0] mem [0:DEPTH-1];
    reg [AW:0]      wr_ptr;
    reg [AW:0]      rd_ptr;

    assign level   = wr_ptr - rd_ptr;
    assign s_ready = (level != DEPTH[AW:0]);
    assign m_valid = (wr_ptr != rd_ptr);
    assign m_data  = mem[rd_ptr[AW-1:0]];

    always @(posedge clk) begin
        if (s_valid && s_ready)
            mem[wr_ptr[AW-1:0]] <= s_data;
    end

    always @(posedge clk) begin
        if (rst) begin
            wr_ptr <= {AW+1{1'b0}};
            rd_ptr <= {AW+1{1'b0}};
        end else begin
            if (s_valid && s_ready)
                wr_ptr <= wr_ptr + 1'b1;
            if (m_valid && m_ready)
                rd_ptr <= rd_ptr + 1'b1;
        end
    end

endmodule

`default_nettype wire
