// SPDX-License-Identifier: MIT
// tl_debounce: WIDTH independent debounce filters for synchronised inputs.
//
// A switch contact bounces for a few milliseconds when it opens or closes;
// a limit switch read straight would trip and release many times.  Each bit
// of sync_in (already through tl_sync_2ff) is followed by q only once it
// has differed from q on STABLE_CLKS consecutive clocks: a bounce or a
// glitch shorter than that is ignored, a real change is passed after
// STABLE_CLKS clocks (the filter's only latency) on q.  RESET_VAL is the output
// in reset: the input's safe level (1 = "open" for a limit switch, so an axis
// is treated as at its limit until its switch has read closed for a while).
`default_nettype none

module tl_debounce #(
    parameter integer WIDTH       = 1,
    parameter integer STABLE_CLKS = 50_000,   // 1 ms at 50 MHz, >= 1
    parameter integer RESET_VAL   = 0         // replicated into every bit
) (
    input  wire             clk,
    input  wire             rst,      // synchronous, active high
    input  wire [WIDTH-1:0] sync_in,  // synchronous (tl_sync_2ff)
    output wire [WIDTH-1:0] q         // debounced
);

    localparam integer CNT_BITS = $clog2(STABLE_CLKS + 1);
    localparam [CNT_BITS-1:0] LAST = STABLE_CLKS[CNT_BITS-1:0] - 1'b1;
    localparam [WIDTH-1:0] RST_VEC = {WIDTH{RESET_VAL[0]}};

    reg [WIDTH-1:0]          out_q;
    reg [CNT_BITS*WIDTH-1:0] cnt;   // consecutive clocks with sync_in != out_q, per bit

    integer i;
    always @(posedge clk) begin
        if (rst) begin
            out_q <= RST_VEC;
            cnt <= {CNT_BITS*WIDTH{1'b0}};
        end else begin
            for (i = 0; i < WIDTH; i = i + 1) begin
                if (sync_in[i] == out_q[i]) begin
                    cnt[i*CNT_BITS +: CNT_BITS] <= {CNT_BITS{1'b0}};
                end else if (cnt[i*CNT_BITS +: CNT_BITS] == LAST) begin
                    out_q[i] <= sync_in[i];
                    cnt[i*CNT_BITS +: CNT_BITS] <= {CNT_BITS{1'b0}};
                end else begin
                    cnt[i*CNT_BITS +: CNT_BITS] <= cnt[i*CNT_BITS +: CNT_BITS] + 1'b1;
                end
            end
        end
    end

    assign q = out_q;

endmodule

`default_nettype wire
