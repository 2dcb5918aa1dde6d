// SPDX-License-Identifier: MIT
// tl_pwm_torque: the PWM torque block of the paper's PWM module (section II.C,
// Fig. 6): a signed torque command to H-bridge pins, with the dead-zone
// compensation of eq. (1) and the saturation of eq. (19)/(25).
//
// Period: M = 2^PWM_BITS - 1 ticks of freq_div (so the carrier is
// f_tick / M).  The pin is high for `duty` ticks of the M, so duty 0 is a
// constant low and duty M a constant high: neither shows a glitch pulse, and
// eq. (24)'s 2^N - 1 steps span 0 .. 100 %.
//
// Mapping (docs/pwm_torque.md; torqueloop/oracles/pwm_torque.py: map_duty):
//   cmd == 0 -> duty 0, else
//   duty = min(pw0, pw_max) + round(min(|cmd|, M) * max(pw_max - pw0, 0) / M)
// i.e. any non-zero command skips the dead zone (-PW0, PW0) and lands
// linearly on PW0 .. PW_F (eq. 1 as intended; the printed equation is
// garbled), never above pw_max.  It is pipelined over PIPE_CLOCKS = 3 clocks
// (one multiply per stage at most), computed every clock, and latched only
// at a period start together with the direction: H-bridges must not see a
// duty or direction change mid-period (double buffering).
//
// Safety: the edge that samples enable low or fault high puts the pins in
// the safe state (brake_on_fault = 1: both low sides on; 0: coast, all
// pins low), so they are safe within one clock whatever the command.  The
// bridge resumes only at the next period start with enable high and fault
// low, so no runt pulse follows a fault.  enable and fault must be
// synchronous to clk (pass a comparator or e-stop through sync_2ff first).
// Every pin is a flip-flop output: no combinational gating, no glitches.
`default_nettype none

module tl_pwm_torque #(
    parameter integer PWM_BITS = 10   // duty resolution; period = 2^PWM_BITS - 1 ticks
) (
    input  wire                clk,
    input  wire                rst,            // synchronous, active high: coast, counters cleared
    input  wire                tick,           // from freq_div: advance the period counter
    input  wire [PWM_BITS:0]   cmd,            // signed torque command, -(2^N-1) .. 2^N-1 (-2^N saturates)
    input  wire [PWM_BITS-1:0] pw0,            // dead-zone edge PW0, duty ticks
    input  wire [PWM_BITS-1:0] pw_max,         // full-command duty PW_F (torque limit), duty ticks
    input  wire                enable,         // 0: safe state
    input  wire                fault,          // 1: safe state
    input  wire                brake_on_fault, // safe state: 1 = brake (both low sides on), 0 = coast
    input  wire                dir_mode,       // 0 = BTS7960/IBT-2 (RPWM/LPWM), 1 = PWM + DIR
    output reg                 rpwm,           // IBT-2 forward PWM
    output reg                 lpwm,           // IBT-2 reverse PWM
    output reg                 r_en,           // IBT-2 half-bridge enables; PWM+DIR: bridge enable
    output reg                 l_en,
    output reg                 pwm_out,        // PWM+DIR mode: PWM
    output reg                 dir_out,        // PWM+DIR mode: 1 = reverse
    output reg                 period_start,   // high for the first clock of each period
    output wire [PWM_BITS-1:0] duty_applied,   // duty of the current period, ticks
    output wire                dir_applied,    // direction of the current period, 1 = reverse
    output wire                active          // 1: bridge driven, 0: safe state
);

    localparam integer N = PWM_BITS;
    localparam [N-1:0]   FULL  = {N{1'b1}};           // M = 2^N - 1: full-scale duty and |cmd|
    localparam [N-1:0]   PLAST = {{(N-1){1'b1}}, 1'b0}; // M - 1: last count of a period
    localparam [2*N-1:0] HALF  = {{(N+1){1'b0}}, {(N-1){1'b1}}}; // (M - 1) / 2: round half up

    // ---- stage 1: magnitude with saturation (eq. 19/25), dead-zone edges ----
    wire [N:0] cmd_neg = ~cmd + 1'b1;
    wire [N:0] cmd_abs = cmd[N] ? cmd_neg : cmd;
    // Only -2^N has bit N set in its magnitude: saturate it to -M.
    wire [N-1:0] mag = cmd_abs[N] ? FULL : cmd_abs[N-1:0];

    reg [N-1:0] s1_mag;
    reg         s1_nz;
    reg         s1_neg;
    reg [N-1:0] s1_base;   // PW0, or pw_max if it is below PW0 (the limit wins)
    reg [N-1:0] s1_span;   // PW_F - PW0, or 0

    // ---- stage 2: product, plus half a step for rounding ----
    reg [2*N-1:0] s2_prod;
    reg           s2_nz;
    reg           s2_neg;
    reg [N-1:0]   s2_base;

    // ---- stage 3: divide by M and add the dead-zone edge (eq. 1) ----
    // floor(x / (2^N - 1)) == (x + (x >> N) + 1) >> N for 0 <= x < 2^2N - 2^N
    // (checked exhaustively by tests/test_oracle_pwm_torque.py); x here is at most
    // M*M + (M-1)/2, so the sum stays below 2^2N.  The low N bits are the
    // discarded remainder.
    /* verilator lint_off UNUSEDSIGNAL */
    wire [2*N-1:0] q_sum = s2_prod + {{N{1'b0}}, s2_prod[2*N-1:N]} + 1'b1;
    /* verilator lint_on UNUSEDSIGNAL */
    wire [N-1:0]   q     = q_sum[2*N-1:N];
    reg  [N-1:0] duty_next;
    reg          dir_next;

    always @(posedge clk) begin
        if (rst) begin
            s1_mag    <= {N{1'b0}};
            s1_nz     <= 1'b0;
            s1_neg    <= 1'b0;
            s1_base   <= {N{1'b0}};
            s1_span   <= {N{1'b0}};
            s2_prod   <= {2*N{1'b0}};
            s2_nz     <= 1'b0;
            s2_neg    <= 1'b0;
            s2_base   <= {N{1'b0}};
            duty_next <= {N{1'b0}};
            dir_next  <= 1'b0;
        end else begin
            s1_mag    <= mag;
            s1_nz     <= |cmd;
            s1_neg    <= cmd[N];
            s1_base   <= (pw0 < pw_max) ? pw0 : pw_max;
            s1_span   <= (pw_max > pw0) ? pw_max - pw0 : {N{1'b0}};
            s2_prod   <= s1_mag * s1_span + HALF;
            s2_nz     <= s1_nz;
            s2_neg    <= s1_neg;
            s2_base   <= s1_base;
            duty_next <= s2_nz ? s2_base + q : {N{1'b0}};
            dir_next  <= s2_neg;
        end
    end

    // ---- period counter, double-buffered duty/direction, bridge pins ----
    reg [N-1:0] pcnt;      // ticks into the period, 0 .. M-1
    reg [N-1:0] duty_q;
    reg         dir_q;
    reg         run_q;

    wire         stop   = ~enable | fault;
    wire         start  = tick & (pcnt == PLAST);
    wire [N-1:0] pcnt_n = ~tick ? pcnt : (start ? {N{1'b0}} : pcnt + 1'b1);
    wire [N-1:0] duty_n = start ? duty_next : duty_q;
    wire         dir_n  = start ? dir_next : dir_q;
    wire         run_n  = ~stop & (start | run_q);
    wire         on_n   = (pcnt_n < duty_n);

    always @(posedge clk) begin
        if (rst) begin
            pcnt         <= PLAST;   // the first tick starts a period
            duty_q       <= {N{1'b0}};
            dir_q        <= 1'b0;
            run_q        <= 1'b0;
            period_start <= 1'b0;
            rpwm         <= 1'b0;
            lpwm         <= 1'b0;
            r_en         <= 1'b0;
            l_en         <= 1'b0;
            pwm_out      <= 1'b0;
            dir_out      <= 1'b0;
        end else begin
            pcnt         <= pcnt_n;
            duty_q       <= duty_n;
            dir_q        <= dir_n;
            run_q        <= run_n;
            period_start <= start;
            // Pins show the state after this edge, so no output lags its counter.
            if (!run_n) begin
                rpwm    <= 1'b0;
                lpwm    <= 1'b0;
                r_en    <= brake_on_fault;
                l_en    <= brake_on_fault;
                pwm_out <= 1'b0;
                dir_out <= 1'b0;
            end else if (dir_mode) begin
                rpwm    <= 1'b0;
                lpwm    <= 1'b0;
                r_en    <= 1'b1;
                l_en    <= 1'b1;
                pwm_out <= on_n;
                dir_out <= dir_n;
            end else begin
                rpwm    <= on_n & ~dir_n;
                lpwm    <= on_n & dir_n;
                r_en    <= 1'b1;
                l_en    <= 1'b1;
                pwm_out <= 1'b0;
                dir_out <= 1'b0;
            end
        end
    end

    assign duty_applied = duty_q;
    assign dir_applied  = dir_q;
    assign active       = run_q;

endmodule

`default_nettype wire
