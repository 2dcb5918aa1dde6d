// SPDX-License-Identifier: MIT
// tl_reset_sync: asynchronous assertion, synchronous release of reset.
//
// The board's reset button (RESET_N) and the PLL-locked signal are
// asynchronous to CLOCK_50.  Asserting reset must not wait for a clock (the
// drives must go safe at once), but releasing it must happen on a clock edge
// with STAGES flops of settling, or half the design could leave reset one
// cycle before the other half.  rst_out is active high, for the cores.
`default_nettype none

module tl_reset_sync #(
    parameter integer STAGES = 2   // >= 2
) (
    input  wire clk,
    input  wire arst_n,    // asynchronous, active low
    output wire rst_out    // synchronous release, active high
);

    // Power up in reset (Quartus honours the initial value): the level-sensitive
    // clear of the real flops holds them while arst_n is low, but a simulator
    // sees no edge if arst_n is already low at time zero.
    // The initial value and the reset value are meant to be the same here.
    /* verilator lint_off PROCASSINIT */
    (* altera_attribute = "-name SYNCHRONIZER_IDENTIFICATION FORCED_IF_ASYNCHRONOUS" *)
    reg [STAGES-1:0] chain = {STAGES{1'b1}};
    /* verilator lint_on PROCASSINIT */

    always @(posedge clk or negedge arst_n) begin
        if (!arst_n)
            chain <= {STAGES{1'b1}};
        else
            chain <= {chain[STAGES-2:0], 1'b0};
    end

    assign rst_out = chain[STAGES-1];

endmodule

`default_nettype wire
