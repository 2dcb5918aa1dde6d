// SPDX-License-Identifier: MIT
// soc_sys: identification registers, watchdog and the safety latch.
//
// A stage that moves unasked is the worst failure of this machine, so the
// path that stops the drives does not depend on firmware: the e-stop input,
// the bridge fault inputs and the watchdog set cause bits of a latch in
// hardware, and `safe` (latch set, or a cause present right now) forces the
// bridge outputs low in soc_safety_gate.  Firmware can only clear a cause
// bit (W1C) once its cause has gone; it cannot clear a latch while the
// e-stop is still pressed.  Layout: SYS block of torqueloop/spec/regmap.toml.
// Bus slave: see tl_soc_timer.v.
// the register map's TL_* names (generated; the include guard makes a second include empty)
`include "regmap.vh"
`default_nettype none

module tl_soc_sys #(
    parameter [31:0] BUILD_ID = 32'd0,
    parameter [31:0] CLK_HZ   = `TL_CLK_HZ
) (
    input  wire        clk,
    input  wire        rst,
    input  wire        estop,        // asynchronous, 1 = stop (wire the NC contact so a break reads 1)
    input  wire [1:0]  bridge_fault, // asynchronous, 1 = fault, per axis
    output wire [1:0]  bridge_fault_s, // bridge_fault synchronised, for the axes' status
    output wire        safe,         // 1 = drives must be off
    output wire        safety_event, // one-cycle pulse: a cause bit was newly set
    // bus (docs/soc.md, Bus): tl_soc_fabric's request to this page, this block's answer
    /* verilator lint_off UNUSEDSIGNAL */  // a block reads the bits of the bundle it needs
    input  wire [`TL_BUS_REQ_WIDTH-1:0] bus_req,
    /* verilator lint_on UNUSEDSIGNAL */
    output wire [`TL_BUS_RSP_WIDTH-1:0] bus_rsp    // combinational; the fabric registers it
);

    localparam [31:0] ID_RESET      = `TL_SYS_ID_RESET;
    localparam [31:0] VERSION_RESET = `TL_SYS_VERSION_RESET;

    reg  [31:0] rdata;          // read decode at the end
    reg         err;
    assign bus_rsp = {err, rdata};   // regmap.vh's layout: TL_BUS_RSP_ERR_LSB = 32

    wire estop_s;
    wire [1:0] fault_s;
    // Reset values 1: a stop input already active at power-up latches at
    // once instead of waiting two cycles for the synchroniser.
    tl_sync_2ff #(.WIDTH(1), .RESET_VAL(1)) u_sync_estop (.clk(clk), .rst(rst), .async_in(estop), .sync_out(estop_s));
    tl_sync_2ff #(.WIDTH(2), .RESET_VAL(0)) u_sync_fault (.clk(clk), .rst(rst), .async_in(bridge_fault), .sync_out(fault_s));

    reg  [31:0] wdog_load;
    reg  [31:0] wdog_cnt;
    reg  [31:0] scratch;
    reg  [3:0]  latch;          // {wdog, fault1, fault0, estop}, as SAFETY[11:8]
    reg         event_q;

    wire        wr    = bus_req[`TL_BUS_REQ_STB_LSB] && bus_req[`TL_BUS_REQ_WE_LSB];
    wire [9:0]  idx   = bus_req[`TL_BUS_REQ_IDX_MSB:`TL_BUS_REQ_IDX_LSB];
    wire [31:0] wmask = bus_req[`TL_BUS_REQ_WMASK_MSB:`TL_BUS_REQ_WMASK_LSB];
    wire [31:0] wbits = bus_req[`TL_BUS_REQ_WBITS_MSB:`TL_BUS_REQ_WBITS_LSB];

    wire        kick      = wr && (idx == `TL_SYS_WDOG_KICK_IDX || idx == `TL_SYS_WDOG_LOAD_IDX);
    wire        wdog_fire = (wdog_load != 32'd0) && (wdog_cnt == 32'd1) && !kick;
    wire [3:0]  cause     = {wdog_fire, fault_s, estop_s};
    wire [3:0]  clr       = (wr && idx == `TL_SYS_SAFETY_IDX)
                            ? wbits[`TL_SYS_SAFETY_WDOG_LSB:`TL_SYS_SAFETY_ESTOP_LSB] : 4'd0;

    always @(posedge clk) begin
        if (rst) begin
            wdog_load <= `TL_SYS_WDOG_LOAD_RESET;
            wdog_cnt  <= 32'd0;
            scratch   <= `TL_SYS_SCRATCH_RESET;
            // ESTOP set: no automatic restart after reset (firmware acknowledges).
            latch     <= 4'b0001;
            event_q   <= 1'b0;
        end else begin
            // A cause present in the clear cycle keeps its bit set.
            latch   <= (latch & ~clr) | cause;
            event_q <= |(cause & ~latch);
            if (wr && idx == `TL_SYS_WDOG_LOAD_IDX)
                wdog_load <= (wdog_load & ~wmask) | wbits;
            if (wr && idx == `TL_SYS_SCRATCH_IDX)
                scratch <= (scratch & ~wmask) | wbits;
            // Watchdog: counts down from WDOG_LOAD; reaching 1 fires and reloads.
            if (kick)
                wdog_cnt <= (idx == `TL_SYS_WDOG_LOAD_IDX) ? ((wdog_load & ~wmask) | wbits) : wdog_load;
            else if (wdog_load == 32'd0)
                wdog_cnt <= 32'd0;
            else if (wdog_cnt <= 32'd1)
                wdog_cnt <= wdog_load;
            else
                wdog_cnt <= wdog_cnt - 32'd1;
        end
    end

    assign safe           = (|latch) || (|cause);
    assign bridge_fault_s = fault_s;
    assign safety_event = event_q;

    // Read decode: this block's registers only; tl_soc_fabric acknowledges.
    always @(*) begin
        {err, rdata} = 33'd0;
        case (idx)
            `TL_SYS_ID_IDX:        rdata = ID_RESET;
            `TL_SYS_VERSION_IDX:   rdata = VERSION_RESET;
            `TL_SYS_BUILD_ID_IDX:  rdata = BUILD_ID;
            `TL_SYS_CLK_HZ_IDX:    rdata = CLK_HZ;
            `TL_SYS_SAFETY_IDX: begin
                rdata[`TL_SYS_SAFETY_SAFE_LSB]     = safe;
                rdata[`TL_SYS_SAFETY_ESTOP_IN_LSB] = estop_s;
                rdata[`TL_SYS_SAFETY_WDOG_LSB:`TL_SYS_SAFETY_ESTOP_LSB] = latch;
            end
            `TL_SYS_WDOG_LOAD_IDX: rdata = wdog_load;
            `TL_SYS_WDOG_KICK_IDX: rdata = 32'd0;
            `TL_SYS_SCRATCH_IDX:   rdata = scratch;
            default:               err   = 1'b1;
        endcase
    end

endmodule

`default_nettype wire
