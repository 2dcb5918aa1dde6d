// SPDX-License-Identifier: MIT
// Safety properties of quad_decoder, proven by Yosys SAT (make lint):
//  1. for any run-time sample_div and filter_len, the position changes by at
//     most one count per clock unless pos_load was given (the 32-bit wrap
//     from 2^31 - 1 to -2^31 counts as one step, as it is one in two's
//     complement);
//  2. with the sampling prescaler set to SAMPLE_DIV, two counts are at least
//     SAMPLE_DIV + 1 clocks apart: at most one count per sample;
//  3. an illegal transition never moves the position.
`default_nettype none

module quad_decoder_props #(
    parameter integer SAMPLE_DIV = 3
) (
    input wire        clk,
    input wire        rst,
    input wire        enc_a,
    input wire        enc_b,
    input wire        enc_z,
    input wire [3:0]  sample_div,
    input wire [1:0]  filter_len,
    input wire        pos_load,
    input wire [31:0] pos_load_val,
    input wire        illegal_clear,
    input wire        index_arm
);
    wire [31:0] pos_any, pos_fix;
    wire [3:0]  ill_any;

    tl_quad_decoder #(.FILTER_BITS(2), .DIV_BITS(4), .TS_BITS(4), .ILLEGAL_BITS(4)) dut_any (
        .clk(clk), .rst(rst), .enc_a(enc_a), .enc_b(enc_b), .enc_z(enc_z),
        .sample_div(sample_div), .filter_len(filter_len),
        .pos_load(pos_load), .pos_load_val(pos_load_val),
        .illegal_clear(illegal_clear), .index_arm(index_arm),
        .position(pos_any), .dir(), .illegal_count(ill_any), .illegal_flag(),
        .index_pos(), .index_seen(), .index_armed(),
        .timestamp(), .last_edge_time(), .edge_interval(), .enc_filtered()
    );

    // Property 2 instance: fixed prescaler, no loads, free filter length.
    tl_quad_decoder #(.FILTER_BITS(2), .DIV_BITS(4), .TS_BITS(4), .ILLEGAL_BITS(4)) dut_fix (
        .clk(clk), .rst(rst), .enc_a(enc_a), .enc_b(enc_b), .enc_z(enc_z),
        .sample_div(SAMPLE_DIV[3:0]), .filter_len(filter_len),
        .pos_load(1'b0), .pos_load_val(32'd0),
        .illegal_clear(1'b0), .index_arm(1'b0),
        .position(pos_fix), .dir(), .illegal_count(), .illegal_flag(),
        .index_pos(), .index_seen(), .index_armed(),
        .timestamp(), .last_edge_time(), .edge_interval(), .enc_filtered()
    );

    reg        past_valid = 1'b0;
    reg        past_ctl   = 1'b0;   // rst or pos_load in the previous clock
    reg        past_clr   = 1'b0;
    reg        past_rst   = 1'b0;
    reg [31:0] past_any   = 32'd0;
    reg [31:0] past_fix   = 32'd0;
    reg [3:0]  past_ill   = 4'd0;
    reg [3:0]  since_fix  = 4'hf;   // clocks since dut_fix last counted, saturating (15: none yet)

    always @(posedge clk) begin
        past_valid <= 1'b1;
        past_ctl   <= rst | pos_load;
        past_clr   <= illegal_clear;
        past_rst   <= rst;
        past_any   <= pos_any;
        past_fix   <= pos_fix;
        past_ill   <= ill_any;
        if (rst)
            since_fix <= 4'hf;
        else if (past_valid && !past_rst && pos_fix != past_fix)
            since_fix <= 4'd0;
        else if (since_fix != 4'hf)
            since_fix <= since_fix + 4'd1;
    end

    wire [31:0] delta_any = pos_any - past_any;

    always @(*) begin
        if (past_valid && !past_ctl)
            assert (delta_any == 32'd0 || delta_any == 32'd1 || delta_any == 32'hffff_ffff);
        if (past_valid && !past_rst && pos_fix != past_fix)
            assert (since_fix >= SAMPLE_DIV);
        if (past_valid && !past_ctl && !past_clr && ill_any != past_ill)
            assert (pos_any == past_any);
    end
endmodule

`default_nettype wire
