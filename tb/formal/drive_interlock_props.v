// SPDX-License-Identifier: MIT
// Safety properties of drive_interlock, proven by Yosys SAT (make lint),
// for every input sequence:
//  - nothing reaches a bridge pin unless the drives were armed the clock
//    before (the output register samples `armed`);
//  - a stop request disarms by the next clock, and a disarmed block
//    stays disarmed while the stop is held;
//  - arming needs arm_sw to have been low at some clock after reset and
//    not up during a later stop (a fresh rising edge), and no stop;
//  - liveness: the drives are never armed while the SoC's watchdog is not
//    alive, a watchdog expiry disarms by the next clock and latches
//    `tripped`, and arming after an expiry needs the switch moved down and
//    up again while alive (a physical re-arm);
//  - reset leaves every bridge input low and the drives disarmed.
`default_nettype none

module drive_interlock_props #(
    parameter integer AXES              = 2,
    parameter integer FAULT_FILTER_CLKS = 3
) (
    input wire            clk,
    input wire            rst,
    input wire            estop,
    input wire            arm_sw,
    input wire [AXES-1:0] fault,
    input wire            alive,
    input wire [AXES-1:0] rpwm_in,
    input wire [AXES-1:0] lpwm_in,
    input wire [AXES-1:0] r_en_in,
    input wire [AXES-1:0] l_en_in
);
    wire [AXES-1:0] rpwm_out, lpwm_out, r_en_out, l_en_out, fault_latched;
    wire            armed, tripped;

    tl_drive_interlock #(.AXES(AXES), .FAULT_FILTER_CLKS(FAULT_FILTER_CLKS)) dut (
        .clk(clk), .rst(rst), .estop(estop), .arm_sw(arm_sw), .fault(fault), .alive(alive),
        .rpwm_in(rpwm_in), .lpwm_in(lpwm_in), .r_en_in(r_en_in), .l_en_in(l_en_in),
        .rpwm_out(rpwm_out), .lpwm_out(lpwm_out), .r_en_out(r_en_out), .l_en_out(l_en_out),
        .armed(armed), .tripped(tripped), .fault_latched(fault_latched)
    );

    // Observers of the previous clock, independent of the design's registers.
    reg past_valid = 1'b0;
    reg rst_d      = 1'b0;
    reg estop_d    = 1'b0;
    reg armed_d    = 1'b0;
    // arm_sw seen low (outside reset) and not followed by a stop while up:
    // the only way to a rising edge that may arm.
    reg low_seen   = 1'b0;
    reg alive_d    = 1'b0;
    reg lost_d     = 1'b0;   // the watchdog expired at the last clock (outside reset)
    always @(posedge clk) begin
        past_valid <= 1'b1;
        rst_d      <= rst;
        estop_d    <= estop;
        armed_d    <= armed;
        alive_d    <= alive;
        lost_d     <= !rst && !rst_d && alive_d && !alive;
        if (rst)
            low_seen <= 1'b0;
        else if (!arm_sw)
            low_seen <= 1'b1;
        else if (estop || !alive)
            low_seen <= 1'b0;
    end

    wire any_out = |{rpwm_out, lpwm_out, r_en_out, l_en_out};

    always @(*) begin
        if (past_valid && !armed_d)
            assert (!any_out);
        if (past_valid && rst_d)
            assert (!armed && !any_out);
        if (past_valid && estop_d)
            assert (!armed);
        if (past_valid && armed && !armed_d)
            assert (low_seen && !estop_d && alive_d);
        if (past_valid && !alive_d && !rst_d)
            assert (!armed);
        if (past_valid && lost_d)
            assert (tripped);
        if (past_valid && armed)
            assert (!tripped);
    end
endmodule

`default_nettype wire
