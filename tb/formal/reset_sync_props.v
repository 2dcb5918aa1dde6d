// SPDX-License-Identifier: MIT
// Safety properties of reset_sync, proven by Yosys SAT (make lint):
//  - while arst_n is low, rst_out is high (no clock needed: async2sync keeps
//    the asynchronous path combinational);
//  - rst_out falls only after arst_n has been high for STAGES clock edges.
`default_nettype none

module reset_sync_props #(
    parameter integer STAGES = 2
) (
    input wire clk,
    input wire arst_n
);
    wire rst_out;
    tl_reset_sync #(.STAGES(STAGES)) dut (.clk(clk), .arst_n(arst_n), .rst_out(rst_out));

    // Count of consecutive edges with arst_n high, saturating at STAGES.
    reg [3:0] high_edges = 4'd0;
    always @(posedge clk) begin
        if (!arst_n)
            high_edges <= 4'd0;
        else if (high_edges < STAGES)
            high_edges <= high_edges + 4'd1;
    end

    always @(*) begin
        if (!arst_n)
            assert (rst_out);
        if (high_edges < STAGES)
            assert (rst_out);
    end
endmodule

`default_nettype wire
