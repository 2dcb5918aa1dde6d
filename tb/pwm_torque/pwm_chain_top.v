// SPDX-License-Identifier: MIT
// Test top: freq_div ticks driving pwm_torque, as the SoC wires them, so the
// bench can check the carrier on the pins against torqueloop/models/freq_div.py:
// carrier_hz() (what the characterisation flow and firmware rely on).
`default_nettype none

module pwm_chain_top #(
    parameter integer CLK_HZ           = 50_000_000,
    parameter integer PWM_BITS         = 6,
    parameter integer DIV_BITS         = 16,
    parameter integer DEFAULT_DIV      = 40
) (
    input  wire                clk,
    input  wire                rst,
    input  wire                div_we,
    input  wire [DIV_BITS-1:0] div_in,
    input  wire [PWM_BITS:0]   cmd,
    input  wire [PWM_BITS-1:0] pw0,
    input  wire [PWM_BITS-1:0] pw_max,
    input  wire                enable,
    output wire [DIV_BITS-1:0] div,
    output wire                rpwm,
    output wire                lpwm,
    output wire                period_start
);
    wire tick;
    // The bench watches RPWM/LPWM only; the other outputs are left open.
    /* verilator lint_off UNUSEDSIGNAL */
    wire r_en, l_en, pwm_out, dir_out, dir_applied, active;
    wire [PWM_BITS-1:0] duty_applied;
    /* verilator lint_on UNUSEDSIGNAL */

    tl_freq_div #(.DIV_BITS(DIV_BITS), .DEFAULT_DIV(DEFAULT_DIV)) u_div (
        .clk(clk), .rst(rst), .div_we(div_we), .div_in(div_in), .div(div), .tick(tick)
    );

    tl_pwm_torque #(.PWM_BITS(PWM_BITS)) u_pwm (
        .clk(clk), .rst(rst), .tick(tick), .cmd(cmd), .pw0(pw0), .pw_max(pw_max),
        .enable(enable), .fault(1'b0), .brake_on_fault(1'b1), .dir_mode(1'b0),
        .rpwm(rpwm), .lpwm(lpwm), .r_en(r_en), .l_en(l_en), .pwm_out(pwm_out), .dir_out(dir_out),
        .period_start(period_start), .duty_applied(duty_applied), .dir_applied(dir_applied),
        .active(active)
    );
endmodule

`default_nettype wire
