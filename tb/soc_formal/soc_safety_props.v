// SPDX-License-Identifier: MIT
// Safety properties of the SoC's stop path (soc_sys latch + soc_safety_gate),
// proven by Yosys SAT k-induction (make lint), for every input sequence:
// any bus traffic, any e-stop/fault waveform, any PWM request.
//  1. While the e-stop pin is high, or in reset, or while `safe`, no PWM pin
//     of either axis is high (combinational: holds with no clock edge).
//  2. Once the e-stop has been high on 3 consecutive clock edges (through
//     its synchroniser), `safe` is set, and it stays set as long as the
//     e-stop is high, whatever firmware writes.
//  3. `safe` never falls on its own: only in the cycle after a bus write to
//     SYS.SAFETY (firmware's acknowledgement), and never straight out of
//     reset - so a reset or power-up never restarts a drive by itself.
//  4. The hardware watchdog: once armed it stays armed until reset (no bus
//     write disarms it); alive only while armed; armed but not alive (expired)
//     holds `safe`; and it comes back alive only in the cycle after a write
//     to WDOG_KICK or WDOG_ARM.  With the invariants asserted inside
//     tl_soc_sys (WDOG_LOAD frozen once armed, the count falls by one per
//     clock unless the kick sequence restarts it, expiry at 1), an armed
//     watchdog expires within WDOG_LOAD clocks of its last kick, whatever
//     else firmware writes.
// the register map's TL_* names (generated; the include guard makes a second include empty)
`include "regmap.vh"
`default_nettype none

module soc_safety_props (
    input wire        clk,
    input wire        rst,
    input wire [`TL_BUS_REQ_WIDTH-1:0] bus_req,   // any access, any time
    input wire        estop,
    input wire [1:0]  bridge_fault,
    input wire [1:0]  rpwm_in,
    input wire [1:0]  lpwm_in,
    input wire [1:0]  pwm_in
);
    wire        safe, safety_event, wdog_armed, wdog_alive;
    wire [`TL_BUS_RSP_WIDTH-1:0] bus_rsp;
    wire [1:0]  fault_s, rpwm, lpwm, pwm;

    tl_soc_sys dut (
        .clk(clk), .rst(rst), .bus_req(bus_req), .bus_rsp(bus_rsp), .estop(estop), .bridge_fault(bridge_fault),
        .bridge_fault_s(fault_s), .safe(safe), .safety_event(safety_event),
        .wdog_armed(wdog_armed), .wdog_alive(wdog_alive)
    );

    tl_soc_safety_gate #(.N_AXES(2)) gate (
        .rst(rst), .safe(safe), .estop_pin(estop),
        .rpwm_in(rpwm_in), .lpwm_in(lpwm_in), .pwm_in(pwm_in),
        .rpwm(rpwm), .lpwm(lpwm), .pwm(pwm)
    );

    reg [1:0] estop_edges = 2'd0;   // consecutive edges with estop high, saturating at 3
    reg       ack_write_q = 1'b0;   // last edge saw a write to SYS.SAFETY, outside reset
    reg       safe_q      = 1'b1;
    reg       past_valid  = 1'b0;
    reg       rst_q       = 1'b1;
    reg       armed_q     = 1'b0;
    reg       alive_q     = 1'b0;
    reg       wdog_write_q = 1'b0;  // last edge saw a write to WDOG_KICK or WDOG_ARM

    wire [9:0] idx = bus_req[`TL_BUS_REQ_IDX_MSB:`TL_BUS_REQ_IDX_LSB];
    wire       wr  = bus_req[`TL_BUS_REQ_STB_LSB] && bus_req[`TL_BUS_REQ_WE_LSB];

    always @(posedge clk) begin
        rst_q        <= rst;
        armed_q      <= wdog_armed;
        alive_q      <= wdog_alive;
        wdog_write_q <= wr && (idx == `TL_SYS_WDOG_KICK_IDX || idx == `TL_SYS_WDOG_ARM_IDX);
        estop_edges <= !estop ? 2'd0 : (estop_edges == 2'd3 ? 2'd3 : estop_edges + 2'd1);
        ack_write_q <= !rst && bus_req[`TL_BUS_REQ_STB_LSB] && bus_req[`TL_BUS_REQ_WE_LSB]
                       && bus_req[`TL_BUS_REQ_IDX_MSB:`TL_BUS_REQ_IDX_LSB] == `TL_SYS_SAFETY_IDX;
        safe_q      <= safe;
        past_valid  <= 1'b1;
    end

    always @(*) begin
        if (estop || rst || safe)
            assert (rpwm == 2'b00 && lpwm == 2'b00 && pwm == 2'b00);
        if (past_valid && estop_edges == 2'd3)
            assert (safe);
        if (past_valid && safe_q && !safe)
            assert (ack_write_q);
        if (past_valid && !rst && !rst_q && armed_q)
            assert (wdog_armed);
        if (wdog_alive)
            assert (wdog_armed);
        if (wdog_armed && !wdog_alive)
            assert (safe);
        if (past_valid && !rst && !rst_q && wdog_alive && !alive_q)
            assert (wdog_write_q);
    end
endmodule

`default_nettype wire
