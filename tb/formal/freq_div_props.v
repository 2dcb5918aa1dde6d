// SPDX-License-Identifier: MIT
// Properties of freq_div, proven by Yosys SAT (make lint):
//  - two ticks on consecutive clocks only when the divisor is 0 or 1
//    (otherwise the PWM would run faster than the divisor says);
//  - a tick comes at least every 2^DIV_BITS - 1 clocks whatever is written
//    when (no divisor value, no write pattern stalls the PWM: the counter
//    compares with >=, so lowering the divisor never waits for a wrap);
//  - a written divisor is what the counter uses from the next clock, and
//    reset restores the default.
// DIV_BITS is 4 here so that the gap bound is reached by k-induction.
`default_nettype none

module freq_div_props #(
    parameter integer DIV_BITS = 4
) (
    input wire                clk,
    input wire                rst,
    input wire                div_we,
    input wire [DIV_BITS-1:0] div_in
);
    localparam integer GAP_MAX = (2 ** DIV_BITS) - 1;

    wire [DIV_BITS-1:0] div;
    wire                tick;

    // the reset divisor is the register's largest value
    tl_freq_div #(.DIV_BITS(DIV_BITS), .DEFAULT_DIV(GAP_MAX)) dut (
        .clk(clk), .rst(rst), .div_we(div_we), .div_in(div_in), .div(div), .tick(tick)
    );

    reg                past_valid = 1'b0;
    reg                past_tick, past_rst, past_we;
    reg [DIV_BITS-1:0] past_div, past_div_in;
    reg [5:0]          since = 6'd0;   // clocks since the last tick or reset, saturating
    always @(posedge clk) begin
        past_valid  <= 1'b1;
        past_tick   <= tick;
        past_rst    <= rst;
        past_we     <= div_we;
        past_div    <= div;
        past_div_in <= div_in;
        if (rst || tick)
            since <= 6'd0;
        else if (since != 6'd63)
            since <= since + 6'd1;
    end

    always @(*) begin
        if (past_valid && !past_rst) begin
            if (past_tick && tick)
                assert (past_div <= 1);
            if (past_we)
                assert (div == past_div_in);
        end
        if (past_valid && past_rst)
            assert (div == GAP_MAX[DIV_BITS-1:0] && !tick);
        assert (since <= GAP_MAX);
    end
endmodule

`default_nettype wire
