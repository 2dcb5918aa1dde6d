// SPDX-License-Identifier: MIT
// char_bench_top: the paper's PWM module as the characterisation bench
// drives a motor (section II.B with II.C): freq_div makes the tick (eq. 2-4),
// pwm_torque turns a command into IBT-2 pins (eq. 1).  Simulation only: the
// cocotb bench in this folder sets Count_max and the duty, watches the pins
// and hands their waveform to the plant's dynamometer model.
// Forward drive (dir_mode 0: PWM on RPWM, LPWM low), brake as the safe state.
// tb/pwm_torque's chain test runs the same module (its VHDL twin there is
// pwm_chain_top.vhd).
`default_nettype none

module char_bench_top #(
    parameter integer CLK_HZ   = 50_000_000,  // DE0-CV CLOCK_50
    parameter integer PWM_BITS = 10,          // gamma = 2^10 (eq. 2)
    parameter integer DIV_BITS = 16,          // freq_div divisor register width
    parameter integer DEFAULT_DIV = 109       // divisor after reset (109: 448 Hz at 10 bits)
) (
    input  wire                clk,
    input  wire                rst,
    input  wire                div_we,
    input  wire [DIV_BITS-1:0] div_in,        // Count_max (eq. 4)
    input  wire [PWM_BITS:0]   cmd,           // signed torque command
    input  wire [PWM_BITS-1:0] pw0,           // dead-zone edge, duty counts
    input  wire [PWM_BITS-1:0] pw_max,        // full-command duty, duty counts
    input  wire                enable,
    output wire [DIV_BITS-1:0] div,
    output wire                rpwm,
    output wire                lpwm,
    output wire                r_en,
    output wire                l_en,
    output wire                period_start
);

    wire tick;
    /* verilator lint_off UNUSEDSIGNAL */
    wire                pwm_out, dir_out, dir_applied, active;
    wire [PWM_BITS-1:0] duty_applied;
    /* verilator lint_on UNUSEDSIGNAL */

    tl_freq_div #(
        .DIV_BITS(DIV_BITS), .DEFAULT_DIV(DEFAULT_DIV)
    ) u_div (
        .clk(clk), .rst(rst), .div_we(div_we), .div_in(div_in), .div(div), .tick(tick)
    );

    tl_pwm_torque #(
        .PWM_BITS(PWM_BITS)
    ) u_pwm (
        .clk(clk), .rst(rst), .tick(tick), .cmd(cmd), .pw0(pw0), .pw_max(pw_max),
        .enable(enable), .fault(1'b0), .brake_on_fault(1'b1), .dir_mode(1'b0),
        .rpwm(rpwm), .lpwm(lpwm), .r_en(r_en), .l_en(l_en), .pwm_out(pwm_out), .dir_out(dir_out),
        .period_start(period_start), .duty_applied(duty_applied), .dir_applied(dir_applied),
        .active(active)
    );

endmodule

`default_nettype wire
