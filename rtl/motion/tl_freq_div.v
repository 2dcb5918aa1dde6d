// SPDX-License-Identifier: MIT
// tl_freq_div: the frequency generator block of the paper's PWM module
// (section II.C, eq. 2-4, Fig. 5).
//
// Makes a one-clock enable `tick` every `div` clocks.  pwm_torque advances
// its period counter on each tick, so with div = Count_max the tick runs at
// f_pwm = f_motor * 2^PWM_BITS (eq. 2) and the PWM carrier at f_motor.
// Count_max (eq. 3-4) is worked out once, by torqueloop/spec/pwm.py
// (divider_for: the divisor whose carrier is nearest the wanted frequency),
// for the firmware, the host and the reset value: DEFAULT_DIV is the
// register map's FDIV reset (`TL_AXIS_FDIV_DIV_RESET, the paper's 450 Hz), so
// the bridge gets the paper's carrier without firmware.
//
// The divisor is a run-time register because the characterisation flow
// sweeps the frequency (paper section II.B, steps 1-5) and firmware picks
// the optimum per motor.  A write takes effect at once: the counter compares
// with ">=", so lowering the divisor below the current count gives a tick on
// the next clock instead of a wait for a 2^DIV_BITS wrap-around.
// Divisor 0 and 1 both mean a tick every clock (f_pwm = CLK_HZ); nothing
// stalls.  At CLK_HZ = 50 MHz and PWM_BITS = 10 keep div >= 2 for a
// BTS7960 (24.4 kHz carrier; the bridge is rated to 25 kHz).
`default_nettype none

module tl_freq_div #(
    parameter integer DIV_BITS         = 16,          // divisor register width
    parameter integer DEFAULT_DIV      = 109          // divisor after reset, 1 .. 2^DIV_BITS - 1 (109: 448 Hz)
) (
    input  wire                clk,
    input  wire                rst,      // synchronous, active high: divisor back to the default
    input  wire                div_we,   // load div_in into the divisor register
    input  wire [DIV_BITS-1:0] div_in,   // new divisor (Count_max), clocks per tick
    output wire [DIV_BITS-1:0] div,      // divisor register as the counter uses it
    output reg                 tick      // one-clock pulse every max(div, 1) clocks
);

    localparam [DIV_BITS-1:0] DEFAULT_DIV_VEC = DEFAULT_DIV[DIV_BITS-1:0];

    reg  [DIV_BITS-1:0] div_q;
    reg  [DIV_BITS-1:0] cnt;     // clocks since the last tick, 0 .. div-1
    // One bit wider so that cnt + 1 cannot wrap when cnt is at its maximum.
    wire [DIV_BITS:0]   cnt_inc = {1'b0, cnt} + 1'b1;
    wire                wrap    = (cnt_inc >= {1'b0, div_q});

    always @(posedge clk) begin
        if (rst) begin
            div_q <= DEFAULT_DIV_VEC;
            cnt   <= {DIV_BITS{1'b0}};
            tick  <= 1'b0;
        end else begin
            if (div_we)
                div_q <= div_in;
            tick <= wrap;
            cnt  <= wrap ? {DIV_BITS{1'b0}} : cnt_inc[DIV_BITS-1:0];
        end
    end

    assign div = div_q;

endmodule

`default_nettype wire
