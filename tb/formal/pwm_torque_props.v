// SPDX-License-Identifier: MIT
// Safety properties of pwm_torque, proven by Yosys SAT (make lint), from any
// state (no reset needed: every property is about one clock edge):
//  - the clock after enable low or fault high the pins are in the safe state
//    chosen by brake_on_fault (brake: R_EN = L_EN = 1, everything else 0;
//    coast: all pins 0), whatever the command;
//  - RPWM and LPWM are never high together, and neither is high without
//    both enables (no shoot-through command, no PWM into a disabled half);
//  - the applied duty and direction change only with period_start (double
//    buffering: never mid-period);
//  - while the bridge runs, duty 0 keeps every PWM pin low and full-scale
//    duty keeps the active one high (no glitch pulse at either end);
//  - the applied duty never exceeds the pw_max seen when it was mapped, as
//    long as pw_max was held for the pipeline's length.
`default_nettype none

module pwm_torque_props #(
    parameter integer PWM_BITS = 10
) (
    input wire                clk,
    input wire                rst,
    input wire                tick,
    input wire [PWM_BITS:0]   cmd,
    input wire [PWM_BITS-1:0] pw0,
    input wire [PWM_BITS-1:0] pw_max,
    input wire                enable,
    input wire                fault,
    input wire                brake_on_fault,
    input wire                dir_mode
);
    localparam integer N = PWM_BITS;
    localparam [N-1:0] FULL = {N{1'b1}};

    wire rpwm, lpwm, r_en, l_en, pwm_out, dir_out, period_start, dir_applied, active;
    wire [N-1:0] duty_applied;

    tl_pwm_torque #(.PWM_BITS(N)) dut (
        .clk(clk), .rst(rst), .tick(tick), .cmd(cmd), .pw0(pw0), .pw_max(pw_max),
        .enable(enable), .fault(fault), .brake_on_fault(brake_on_fault), .dir_mode(dir_mode),
        .rpwm(rpwm), .lpwm(lpwm), .r_en(r_en), .l_en(l_en), .pwm_out(pwm_out), .dir_out(dir_out),
        .period_start(period_start), .duty_applied(duty_applied), .dir_applied(dir_applied),
        .active(active)
    );

    // Inputs and outputs of the previous clock.
    reg         past_valid = 1'b0;
    reg         past_rst, past_stop, past_brake, past_mode;
    reg [N-1:0] past_duty;
    reg         past_dir;
    // Clocks for which pw_max has been held, saturating (for the limit property).
    reg [2:0]   held = 3'd0;
    reg [N-1:0] pw_max_prev;
    always @(posedge clk) begin
        past_valid  <= 1'b1;
        past_rst    <= rst;
        past_stop   <= !enable || fault;
        past_brake  <= brake_on_fault;
        past_mode   <= dir_mode;
        past_duty   <= duty_applied;
        past_dir    <= dir_applied;
        pw_max_prev <= pw_max;
        if (rst || pw_max != pw_max_prev)
            held <= 3'd0;
        else if (held != 3'd7)
            held <= held + 3'd1;
    end

    always @(*) begin
        // Never both PWM inputs of the IBT-2 high; no PWM into a disabled bridge.
        assert (!(rpwm && lpwm));
        if (rpwm || lpwm || pwm_out)
            assert (r_en && l_en);
        if (past_valid && !past_rst) begin
            // Safe state on the clock after enable low or fault high.
            if (past_stop) begin
                assert (!rpwm && !lpwm && !pwm_out && !dir_out);
                assert (r_en == past_brake && l_en == past_brake);
                assert (!active);
            end
            // Duty and direction change only at a period start.
            if (duty_applied != past_duty || dir_applied != past_dir)
                assert (period_start);
            // Clean ends while running: duty 0 never drives, full scale always does.
            if (active && duty_applied == {N{1'b0}})
                assert (!rpwm && !lpwm && !pwm_out);
            if (active && duty_applied == FULL)
                assert (past_mode ? pwm_out : (dir_applied ? lpwm : rpwm));
        end
        // The torque limit: a duty mapped while pw_max was steady is never above it
        // (pw_max at the latching edge and the PIPE_CLOCKS = 3 edges before it).
        if (period_start && held >= 3'd3)
            assert (duty_applied <= pw_max_prev);
        if (past_rst)
            assert (!rpwm && !lpwm && !r_en && !l_en && !pwm_out && !dir_out && !active);
    end
endmodule

`default_nettype wire
