// SPDX-License-Identifier: MIT
// tl_drive_interlock: the last gate between the SoC and the H-bridge pins.
//
// The IBT-2 modules (BTS7960B, paper Sec. V.A) must never be driven while
// the emergency stop is pressed, after an H-bridge fault, or before the
// operator has armed the drives, whatever the processor or its firmware
// does.  This block sits outside the SoC, in the board top, and ANDs every
// bridge input (RPWM, LPWM, R_EN, L_EN of each axis) with one `armed` flag:
//
//   - after reset the drives are disarmed;
//   - arming takes a rising edge of arm_sw (SW[0] moved up) while no stop
//     and no fault is present: a switch that is already up at power-up, or
//     after a stop, arms nothing until it is moved down and up again;
//   - estop (KEY[0] pressed) or a fault on any axis disarms at once and
//     latches `tripped`; arm_sw down disarms too;
//   - liveness: `alive` is the SoC's hardware watchdog, armed by the boot ROM
//     and fed by the running firmware.  Not alive disarms and blocks arming;
//     alive falling (the watchdog expired: the firmware hung) also latches
//     `tripped`.  Drives are therefore only ever on while a watched firmware
//     runs, and after a hang they stay off until the firmware is alive again
//     *and* the operator re-arms with SW[0] (a physical act).
//
// A fault is an IBT-2 IS line above its fault level, seen through a
// comparator (docs/hardware.md); it must persist FAULT_FILTER_CLKS clocks
// to count, so a switching spike on the comparator output does not trip
// the machine.  The BTS7960 latches its own fault until its enable (INH)
// goes low, which disarming does.
//
// Disarmed, all four inputs of both bridges are low: both half-bridges
// switched off, so the motor coasts (stop category 0: power removed, no
// active braking).  Outputs are registered, so the pins carry no glitches
// of the gating logic.
//
// All inputs are synchronous: the board top passes KEY, SW and the fault
// lines through sync_2ff first.  Latency from a stop request to the pins:
// one clock for `armed`, one for the output register.
`default_nettype none

module tl_drive_interlock #(
    parameter integer AXES              = 2,
    parameter integer FAULT_FILTER_CLKS = 250    // 5 us at 50 MHz, >= 1
) (
    input  wire            clk,
    input  wire            rst,            // synchronous, active high
    input  wire            estop,          // 1 = stop requested (held while pressed)
    input  wire            arm_sw,         // 1 = drives allowed; a rising edge arms
    input  wire [AXES-1:0] fault,          // 1 = bridge reports a fault
    input  wire            alive,          // 1 = the SoC's watchdog is armed and not expired
    // from the SoC
    input  wire [AXES-1:0] rpwm_in,
    input  wire [AXES-1:0] lpwm_in,
    input  wire [AXES-1:0] r_en_in,
    input  wire [AXES-1:0] l_en_in,
    // to the IBT-2 pins
    output reg  [AXES-1:0] rpwm_out,
    output reg  [AXES-1:0] lpwm_out,
    output reg  [AXES-1:0] r_en_out,
    output reg  [AXES-1:0] l_en_out,
    // status (LEDs, SoC)
    output reg             armed,
    output reg             tripped,        // a stop or fault since the last arming
    output reg  [AXES-1:0] fault_latched   // which axis faulted since the last arming
);

    localparam integer FILTER_BITS = $clog2(FAULT_FILTER_CLKS + 1);
    localparam [FILTER_BITS-1:0] FILTER_MAX = FAULT_FILTER_CLKS[FILTER_BITS-1:0];

    reg  [FILTER_BITS*AXES-1:0] fault_cnt;   // consecutive clocks with fault, per axis
    reg  [AXES-1:0]             fault_ok;    // fault present for FAULT_FILTER_CLKS clocks
    reg                         arm_sw_q;    // arm_sw one clock ago, for the rising edge
    reg                         alive_q;     // alive one clock ago, for its falling edge

    wire trip    = estop || (|fault_ok);
    wire lost    = alive_q && !alive;        // the watchdog expired
    wire stop    = trip || !alive;
    wire arm_req = arm_sw && !arm_sw_q;

    integer i;
    always @(posedge clk) begin
        if (rst) begin
            fault_cnt <= {FILTER_BITS*AXES{1'b0}};
            fault_ok  <= {AXES{1'b0}};
        end else begin
            for (i = 0; i < AXES; i = i + 1) begin
                if (!fault[i]) begin
                    fault_cnt[i*FILTER_BITS +: FILTER_BITS] <= {FILTER_BITS{1'b0}};
                    fault_ok[i] <= 1'b0;
                end else if (fault_cnt[i*FILTER_BITS +: FILTER_BITS] == FILTER_MAX - 1'b1) begin
                    fault_ok[i] <= 1'b1;
                end else begin
                    fault_cnt[i*FILTER_BITS +: FILTER_BITS] <=
                        fault_cnt[i*FILTER_BITS +: FILTER_BITS] + 1'b1;
                end
            end
        end
    end

    always @(posedge clk) begin
        if (rst) begin
            // Up at reset counts as "was already up": no arming without a new edge.
            arm_sw_q      <= 1'b1;
            alive_q       <= 1'b0;
            armed         <= 1'b0;
            tripped       <= 1'b0;
            fault_latched <= {AXES{1'b0}};
        end else begin
            arm_sw_q <= arm_sw;
            alive_q  <= alive;
            if (stop) begin
                armed         <= 1'b0;
                tripped       <= tripped | trip | lost;
                fault_latched <= fault_latched | fault_ok;
            end else if (!arm_sw) begin
                armed <= 1'b0;
            end else if (arm_req) begin
                armed         <= 1'b1;
                tripped       <= 1'b0;
                fault_latched <= {AXES{1'b0}};
            end
        end
    end

    always @(posedge clk) begin
        if (rst) begin
            rpwm_out <= {AXES{1'b0}};
            lpwm_out <= {AXES{1'b0}};
            r_en_out <= {AXES{1'b0}};
            l_en_out <= {AXES{1'b0}};
        end else begin
            rpwm_out <= rpwm_in & {AXES{armed}};
            lpwm_out <= lpwm_in & {AXES{armed}};
            r_en_out <= r_en_in & {AXES{armed}};
            l_en_out <= l_en_in & {AXES{armed}};
        end
    end

endmodule

`default_nettype wire
