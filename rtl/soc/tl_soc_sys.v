// SPDX-License-Identifier: MIT
// tl_soc_sys: identification registers, the hardware watchdog and the safety latch.
//
// A stage that moves unasked is the worst failure of this machine, so the
// path that stops the drives does not depend on firmware: the e-stop input,
// the bridge fault inputs and the watchdog set cause bits of a latch in
// hardware, and `safe` (latch set, or a cause present right now) holds the
// PWM blocks safe and forces the PWM pins low in soc_safety_gate.  Firmware
// can only clear a cause bit (W1C) once its cause has gone; it cannot clear
// a latch while the e-stop is still pressed or the watchdog expired.
//
// The watchdog cannot depend on the firmware it watches: it does nothing
// until armed (WDOG_ARM = ARM_KEY with WDOG_LOAD set; the boot ROM does it
// before any image runs), and from then until reset it cannot be disarmed,
// WDOG_LOAD is frozen, and only KICK_A followed by KICK_B on WDOG_KICK
// restarts its count; any other write to WDOG_KICK expires it at once.
// Expired, it stays expired (a latch cause, wdog_alive low: the board's
// drive interlock disarms) until the kick sequence arrives again.  The
// invariants behind "expires within WDOG_LOAD clocks of the last kick" are
// asserted below for the SAT proof (make lint, tb/soc_formal).
// Layout: SYS block of torqueloop/spec/regmap.toml.
// Bus slave: see tl_soc_timer.v.
// the register map's TL_* names (generated; the include guard makes a second include empty)
`include "regmap.vh"
`include "tl_soc_page.vh"
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
    output wire        wdog_armed,   // the watchdog is armed (only reset disarms it)
    output wire        wdog_alive,   // armed and not expired: the board's drive interlock may arm
    // bus (docs/soc.md, Bus; tl_soc_page.vh)
    /* verilator lint_off UNUSEDSIGNAL */  // a block reads the bits of the bundle it needs
    `SOC_PAGE_PORTS
    /* verilator lint_on UNUSEDSIGNAL */
);

    localparam [31:0] ID_RESET      = `TL_SYS_ID_RESET;
    localparam [31:0] VERSION_RESET = `TL_SYS_VERSION_RESET;

    `SOC_PAGE_RSP         // rdata, err: the read decode at the end

    wire estop_s;
    wire [1:0] fault_s;
    // Reset values 1: a stop input already active at power-up latches at
    // once instead of waiting two cycles for the synchroniser.
    tl_sync_2ff #(.WIDTH(1), .RESET_VAL(1)) u_sync_estop (.clk(clk), .rst(rst), .async_in(estop), .sync_out(estop_s));
    tl_sync_2ff #(.WIDTH(2), .RESET_VAL(0)) u_sync_fault (.clk(clk), .rst(rst), .async_in(bridge_fault), .sync_out(fault_s));

    reg  [31:0] wdog_load;
    reg  [31:0] wdog_cnt;       // clocks left; 0 while not armed or expired
    reg         armed;
    reg         expired;
    reg         kick_a;         // the last write to WDOG_KICK was KICK_A
    reg  [31:0] scratch;
    reg  [3:0]  latch;          // {wdog, fault1, fault0, estop}, as SAFETY[11:8]
    reg         event_q;

    `SOC_PAGE_WRITE       // wr, idx, wmask, wbits
    wire        full  = wmask == 32'hFFFF_FFFF;   // keys count only as whole-word writes

    wire        kick_wr   = wr && idx == `TL_SYS_WDOG_KICK_IDX;
    wire        key_a     = kick_wr && full && wbits == `TL_SYS_WDOG_KICK_KEY_KICK_A;
    wire        kick_ok   = armed && kick_wr && kick_a && full && wbits == `TL_SYS_WDOG_KICK_KEY_KICK_B;
    wire        kick_bad  = armed && kick_wr && !key_a && !kick_ok;
    wire        arm_wr    = !armed && wr && idx == `TL_SYS_WDOG_ARM_IDX && full
                            && wbits == `TL_SYS_WDOG_ARM_KEY_ARM_KEY && wdog_load != 32'd0;
    wire        wdog_fire = armed && !expired && !kick_ok && (kick_bad || wdog_cnt == 32'd1);
    wire [3:0]  cause     = {wdog_fire || (expired && !kick_ok), fault_s, estop_s};
    wire [3:0]  clr       = (wr && idx == `TL_SYS_SAFETY_IDX)
                            ? wbits[`TL_SYS_SAFETY_WDOG_LSB:`TL_SYS_SAFETY_ESTOP_LSB] : 4'd0;

    always @(posedge clk) begin
        if (rst) begin
            wdog_load <= `TL_SYS_WDOG_LOAD_RESET;
            wdog_cnt  <= 32'd0;
            armed     <= 1'b0;
            expired   <= 1'b0;
            kick_a    <= 1'b0;
            scratch   <= `TL_SYS_SCRATCH_RESET;
            // ESTOP set: no automatic restart after reset (firmware acknowledges).
            latch     <= 4'b0001;
            event_q   <= 1'b0;
        end else begin
            // A cause present in the clear cycle keeps its bit set.
            latch   <= (latch & ~clr) | cause;
            event_q <= |(cause & ~latch);
            if (wr && idx == `TL_SYS_WDOG_LOAD_IDX && !armed)
                wdog_load <= (wdog_load & ~wmask) | wbits;
            if (wr && idx == `TL_SYS_SCRATCH_IDX)
                scratch <= (scratch & ~wmask) | wbits;
            if (kick_wr)
                kick_a <= key_a;
            if (arm_wr)
                armed <= 1'b1;
            // Armed: counts down from WDOG_LOAD; a kick restarts it; reaching 1 (or a
            // wrong kick) expires it, and it stays expired until the next kick.
            if (arm_wr || kick_ok) begin
                wdog_cnt <= wdog_load;
                expired  <= 1'b0;
            end else if (wdog_fire) begin
                wdog_cnt <= 32'd0;
                expired  <= 1'b1;
            end else if (wdog_cnt != 32'd0) begin
                wdog_cnt <= wdog_cnt - 32'd1;
            end
        end
    end

`ifdef FORMAL
    // Step invariants of "an armed watchdog expires within WDOG_LOAD clocks of
    // its last kick, and nothing but the kick sequence delays it" (proven by
    // tb/soc_formal/soc_safety_props.v's k-induction together with the
    // properties there).
    reg        f_past = 1'b0;
    reg        f_armed_q, f_rst_q, f_kick_q;
    reg [31:0] f_load_q, f_cnt_q;
    always @(posedge clk) begin
        f_past    <= 1'b1;
        f_armed_q <= armed;
        f_rst_q   <= rst;
        f_kick_q  <= arm_wr || kick_ok;
        f_load_q  <= wdog_load;
        f_cnt_q   <= wdog_cnt;
    end
    always @(*) begin
        if (!rst && f_past && !f_rst_q) begin
            if (f_armed_q) begin
                assert (armed);                          // never disarmed
                assert (wdog_load == f_load_q);          // never lengthened (nor changed)
                // counts down by exactly one per clock unless kicked, or expires early
                // (a wrong write to WDOG_KICK): never more time than the count had
                if (!f_kick_q && f_cnt_q > 32'd1)
                    assert (wdog_cnt == f_cnt_q - 32'd1 || expired);
                if (!f_kick_q && f_cnt_q == 32'd1)
                    assert (expired);
            end
        end
        if (f_past) begin   // after the first clock: the state is a reset one or follows from it
            if (armed)
                assert (wdog_load != 32'd0);            // armed only with a timeout, then frozen
            if (armed && !expired)
                assert (wdog_cnt != 32'd0 && wdog_cnt <= wdog_load);
            if (!armed)
                assert (!expired && wdog_cnt == 32'd0);
            if (expired)   // held safe here, and the board's interlock sees it
                assert (wdog_cnt == 32'd0 && latch[3] && safe && !wdog_alive);
        end
    end
`endif

    assign safe           = (|latch) || (|cause);
    assign bridge_fault_s = fault_s;
    assign safety_event = event_q;
    assign wdog_armed   = armed;
    assign wdog_alive   = armed && !expired;

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
                rdata[`TL_SYS_SAFETY_WDOG_ARMED_LSB]   = armed;
                rdata[`TL_SYS_SAFETY_WDOG_EXPIRED_LSB] = expired;
                rdata[`TL_SYS_SAFETY_WDOG_LSB:`TL_SYS_SAFETY_ESTOP_LSB] = latch;
            end
            `TL_SYS_WDOG_LOAD_IDX: rdata = wdog_load;
            `TL_SYS_WDOG_KICK_IDX: rdata = 32'd0;
            `TL_SYS_SCRATCH_IDX:   rdata = scratch;
            `TL_SYS_WDOG_ARM_IDX:  rdata = 32'd0;
            default:               err   = 1'b1;
        endcase
    end

endmodule

`default_nettype wire
