// SPDX-License-Identifier: MIT
// tl_soc_axis: one motor axis as a register page (AXIS layout of
// torqueloop/spec/regmap.toml): the paper's PWM module - frequency generator
// (freq_div, eq. 2-4) and PWM torque block (pwm_torque, eq. 1) - driving one
// IBT-2 bridge, and the quadrature decoder of that axis's encoder.
//
// The cores do the work; this block only holds their settings, strobes
// their commands and reads their state.  `safe` (from soc_sys, synchronous)
// is the PWM block's fault input, so the block enters its own safe state
// within a clock and resumes only at a period start after the latch is
// cleared; soc_safety_gate forces the PWM pins low on top of that.
//
// Limit switches (normally closed to GND, pulled up: 1 = open, tripped or
// wire broken) are synchronised and debounced here; while PWM_CTRL.LIMIT_EN
// is set, the bridge side that drives toward an open switch is held low in
// hardware (RPWM toward the positive end, LPWM toward the negative, PWM in
// PWM+DIR mode by its direction), whatever firmware commands; the other
// direction stays free, so the axis can be driven back out.
// Bus slave: see tl_soc_timer.v.
// the register map's TL_* names (generated; the include guard makes a second include empty)
`include "regmap.vh"
`include "tl_soc_page.vh"
`default_nettype none

module tl_soc_axis #(
    parameter integer LIMIT_DEBOUNCE_CLKS = 50_000   // 1 ms at 50 MHz: contact bounce of a limit switch
) (
    input  wire        clk,
    input  wire        rst,
    // safety
    input  wire        safe,          // synchronous: drives must be off
    input  wire        bridge_fault,  // synchronous (soc_sys synchronises it), status only here
    // encoder pins, asynchronous (quad_decoder synchronises them)
    input  wire        enc_a,
    input  wire        enc_b,
    input  wire        enc_z,
    // limit switches, asynchronous, 1 = open (tripped): negative end, positive end
    input  wire        lim_neg,
    input  wire        lim_pos,
    // bridge pins (before soc_safety_gate)
    output wire        rpwm,
    output wire        lpwm,
    output wire        r_en,
    output wire        l_en,
    output wire        pwm_out,
    output wire        dir_out,
    // interrupt sources
    output wire        period_event,  // PWM period start (pulse)
    output wire        index_event,   // index latched (level, rises once per arm)
    output wire        fault_event,   // illegal encoder transition or bridge fault (level)
    // bus (docs/soc.md, Bus; tl_soc_page.vh)
    `SOC_PAGE_PORTS
);

    localparam integer PWM_BITS = `TL_AXIS_PWM_PW0_PW0_WIDTH;
    localparam integer DIV_BITS = `TL_AXIS_FDIV_DIV_WIDTH;
    localparam integer FLT_BITS = `TL_AXIS_ENC_CFG_FILTER_LEN_WIDTH;
    localparam integer SDV_BITS = `TL_AXIS_ENC_CFG_SAMPLE_DIV_WIDTH;
    localparam integer ILL_BITS = `TL_AXIS_ENC_ILLEGAL_COUNT_WIDTH;

    localparam [31:0] CMD_RESET   = `TL_AXIS_PWM_CMD_RESET;
    localparam [31:0] PW0_RESET   = `TL_AXIS_PWM_PW0_RESET;
    localparam [31:0] PWMAX_RESET = `TL_AXIS_PWM_PWMAX_RESET;
    localparam [31:0] CTRL_RESET  = `TL_AXIS_PWM_CTRL_RESET;
    localparam [31:0] CFG_RESET   = `TL_AXIS_ENC_CFG_RESET;

    `SOC_PAGE_RSP         // rdata, err: the read decode at the end

    `SOC_PAGE_WRITE       // wr, idx, wmask, wbits

    // A register after a write: the written bytes, restricted to the bits `keep` software may change.
    function [31:0] merge(input [31:0] old, input [31:0] mask, input [31:0] bits, input [31:0] keep);
        merge = (old & ~(mask & keep)) | (bits & keep);
    endfunction

    // --- settings held here ----------------------------------------------------------
    reg [31:0] cmd_q, pw0_q, pwmax_q, ctrl_q, cfg_q;

    always @(posedge clk) begin
        if (rst) begin
            cmd_q   <= CMD_RESET;
            pw0_q   <= PW0_RESET;
            pwmax_q <= PWMAX_RESET;
            ctrl_q  <= CTRL_RESET;
            cfg_q   <= CFG_RESET;
        end else if (wr) begin
            case (idx)
                `TL_AXIS_PWM_CMD_IDX:   cmd_q   <= merge(cmd_q, wmask, wbits, `TL_AXIS_PWM_CMD_RW_MASK);
                `TL_AXIS_PWM_PW0_IDX:   pw0_q   <= merge(pw0_q, wmask, wbits, `TL_AXIS_PWM_PW0_RW_MASK);
                `TL_AXIS_PWM_PWMAX_IDX: pwmax_q <= merge(pwmax_q, wmask, wbits, `TL_AXIS_PWM_PWMAX_RW_MASK);
                `TL_AXIS_PWM_CTRL_IDX:  ctrl_q  <= merge(ctrl_q, wmask, wbits, `TL_AXIS_PWM_CTRL_RW_MASK);
                `TL_AXIS_ENC_CFG_IDX:   cfg_q   <= merge(cfg_q, wmask, wbits, `TL_AXIS_ENC_CFG_RW_MASK);
                default: ;
            endcase
        end
    end

    // --- limit switches: synchronised, debounced, and the hardware block -------------------
    wire [1:0] lim_s, lim_d;   // {positive, negative}
    tl_sync_2ff #(.WIDTH(2), .RESET_VAL(0)) u_sync_lim (
        .clk(clk), .rst(rst), .async_in({lim_pos, lim_neg}), .sync_out(lim_s));
    tl_debounce #(.WIDTH(2), .STABLE_CLKS(LIMIT_DEBOUNCE_CLKS), .RESET_VAL(0)) u_deb_lim (
        .clk(clk), .rst(rst), .sync_in(lim_s), .q(lim_d));
    wire block_neg = ctrl_q[`TL_AXIS_PWM_CTRL_LIMIT_EN_LSB] && lim_d[0];
    wire block_pos = ctrl_q[`TL_AXIS_PWM_CTRL_LIMIT_EN_LSB] && lim_d[1];
    wire rpwm_core, lpwm_core, pwm_core;
    assign rpwm    = rpwm_core && !block_pos;
    assign lpwm    = lpwm_core && !block_neg;
    assign pwm_out = pwm_core && !(dir_out ? block_neg : block_pos);

    // --- frequency generator (eq. 2-4) ----------------------------------------------------
    wire [DIV_BITS-1:0] div;
    wire                tick;
    /* verilator lint_off UNUSEDSIGNAL */
    wire [31:0]         div_merged = merge({{(32-DIV_BITS){1'b0}}, div}, wmask, wbits, 32'hFFFF_FFFF);
    /* verilator lint_on UNUSEDSIGNAL */

    tl_freq_div #(
        .DIV_BITS(DIV_BITS),
        .DEFAULT_DIV(`TL_AXIS_FDIV_RESET)   // the register map's FDIV reset (system.toml: 450 Hz); DIV is its only field
    ) u_freq_div (
        .clk(clk), .rst(rst),
        .div_we(wr && idx == `TL_AXIS_FDIV_IDX), .div_in(div_merged[DIV_BITS-1:0]),
        .div(div), .tick(tick)
    );

    // --- PWM torque block (eq. 1) -----------------------------------------------------------
    wire [PWM_BITS-1:0] duty_applied;
    wire                dir_applied;
    wire                active;

    tl_pwm_torque #(.PWM_BITS(PWM_BITS)) u_pwm (
        .clk(clk), .rst(rst), .tick(tick),
        .cmd(cmd_q[PWM_BITS:0]), .pw0(pw0_q[PWM_BITS-1:0]), .pw_max(pwmax_q[PWM_BITS-1:0]),
        .enable(ctrl_q[`TL_AXIS_PWM_CTRL_ENABLE_LSB]), .fault(safe),
        .brake_on_fault(ctrl_q[`TL_AXIS_PWM_CTRL_BRAKE_LSB]),
        .dir_mode(ctrl_q[`TL_AXIS_PWM_CTRL_DIR_MODE_LSB]),
        .rpwm(rpwm_core), .lpwm(lpwm_core), .r_en(r_en), .l_en(l_en), .pwm_out(pwm_core), .dir_out(dir_out),
        .period_start(period_event), .duty_applied(duty_applied), .dir_applied(dir_applied),
        .active(active)
    );

    // --- quadrature decoder -------------------------------------------------------------------
    wire [31:0]         position, index_pos, last_edge_time, edge_interval, timestamp;
    wire                enc_dir, illegal_flag, index_seen, index_armed;
    wire [ILL_BITS-1:0] illegal_count;
    wire [2:0]          enc_filtered;
    wire [31:0]         pos_merged = merge(position, wmask, wbits, 32'hFFFF_FFFF);
    wire                cmd_wr     = wr && idx == `TL_AXIS_ENC_CMD_IDX;

    tl_quad_decoder #(
        .FILTER_BITS(FLT_BITS), .DIV_BITS(SDV_BITS), .TS_BITS(32), .ILLEGAL_BITS(ILL_BITS)
    ) u_dec (
        .clk(clk), .rst(rst), .enc_a(enc_a), .enc_b(enc_b), .enc_z(enc_z),
        .sample_div(cfg_q[`TL_AXIS_ENC_CFG_SAMPLE_DIV_MSB:`TL_AXIS_ENC_CFG_SAMPLE_DIV_LSB]),
        .filter_len(cfg_q[`TL_AXIS_ENC_CFG_FILTER_LEN_MSB:`TL_AXIS_ENC_CFG_FILTER_LEN_LSB]),
        .pos_load(wr && idx == `TL_AXIS_ENC_POS_IDX), .pos_load_val(pos_merged),
        .illegal_clear(cmd_wr && wbits[`TL_AXIS_ENC_CMD_ILLEGAL_CLEAR_LSB]),
        .index_arm(cmd_wr && wbits[`TL_AXIS_ENC_CMD_INDEX_ARM_LSB]),
        .position(position), .dir(enc_dir), .illegal_count(illegal_count), .illegal_flag(illegal_flag),
        .index_pos(index_pos), .index_seen(index_seen), .index_armed(index_armed),
        .timestamp(timestamp), .last_edge_time(last_edge_time), .edge_interval(edge_interval),
        .enc_filtered(enc_filtered)
    );

    assign index_event = index_seen;
    assign fault_event = illegal_flag | bridge_fault;

    // --- read decode: this block's registers only; tl_soc_fabric acknowledges ---------------
    always @(*) begin
        {err, rdata} = 33'd0;
        case (idx)
            `TL_AXIS_FDIV_IDX:       rdata[DIV_BITS-1:0] = div;
            `TL_AXIS_PWM_CMD_IDX:    rdata = cmd_q;
            `TL_AXIS_PWM_PW0_IDX:    rdata = pw0_q;
            `TL_AXIS_PWM_PWMAX_IDX:  rdata = pwmax_q;
            `TL_AXIS_PWM_CTRL_IDX:   rdata = ctrl_q;
            `TL_AXIS_PWM_STATUS_IDX: begin
                rdata[`TL_AXIS_PWM_STATUS_ACTIVE_LSB]       = active;
                rdata[`TL_AXIS_PWM_STATUS_DIR_LSB]          = dir_applied;
                rdata[`TL_AXIS_PWM_STATUS_FORCED_LSB]       = safe;
                rdata[`TL_AXIS_PWM_STATUS_BRIDGE_FAULT_LSB] = bridge_fault;
                rdata[`TL_AXIS_PWM_STATUS_LIM_NEG_LSB]      = lim_d[0];
                rdata[`TL_AXIS_PWM_STATUS_LIM_POS_LSB]      = lim_d[1];
                rdata[`TL_AXIS_PWM_STATUS_DUTY_MSB:`TL_AXIS_PWM_STATUS_DUTY_LSB] = duty_applied;
            end
            `TL_AXIS_ENC_POS_IDX:    rdata = position;
            `TL_AXIS_ENC_CFG_IDX:    rdata = cfg_q;
            `TL_AXIS_ENC_STATUS_IDX: begin
                rdata[`TL_AXIS_ENC_STATUS_DIR_LSB]         = enc_dir;
                rdata[`TL_AXIS_ENC_STATUS_ILLEGAL_LSB]     = illegal_flag;
                rdata[`TL_AXIS_ENC_STATUS_INDEX_SEEN_LSB]  = index_seen;
                rdata[`TL_AXIS_ENC_STATUS_INDEX_ARMED_LSB] = index_armed;
                rdata[`TL_AXIS_ENC_STATUS_Z_LSB:`TL_AXIS_ENC_STATUS_A_LSB] = enc_filtered;
            end
            `TL_AXIS_ENC_ILLEGAL_IDX:       rdata[ILL_BITS-1:0] = illegal_count;
            `TL_AXIS_ENC_INDEX_POS_IDX:     rdata = index_pos;
            `TL_AXIS_ENC_EDGE_TIME_IDX:     rdata = last_edge_time;
            `TL_AXIS_ENC_EDGE_INTERVAL_IDX: rdata = edge_interval;
            `TL_AXIS_ENC_TIMESTAMP_IDX:     rdata = timestamp;
            `TL_AXIS_ENC_CMD_IDX:           rdata = 32'd0;
            default:                        err   = 1'b1;
        endcase
    end

endmodule

`default_nettype wire
