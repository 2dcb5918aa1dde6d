// SPDX-License-Identifier: MIT
// soc_timer: RISC-V machine timer (mtime, mtimecmp) and software interrupt (msip).
//
// mtime counts clock cycles (CLOCK_50: 20 ns), so control-loop periods and
// encoder timestamps share one time base.  irq_timer is the level
// mtime >= mtimecmp, as the privileged spec defines it; mtimecmp resets to
// all ones so no interrupt fires before firmware arms it.  Register layout:
// TIMER block of torqueloop/spec/regmap.toml.  Slave contract as in soc_ram.v.
`default_nettype none

module tl_soc_timer (
    input  wire        clk,
    input  wire        rst,
    input  wire        req,
    input  wire        we,
    input  wire [3:0]  be,
    /* verilator lint_off UNUSEDSIGNAL */  // addr[1:0]: byte lanes come from be
    input  wire [11:0] addr,
    /* verilator lint_on UNUSEDSIGNAL */
    input  wire [31:0] wdata,
    output reg         ack,
    output reg         err,
    output reg  [31:0] rdata,
    output wire [63:0] mtime,
    output wire        irq_timer,
    output wire        irq_software
);

    reg [63:0] mtime_q;
    reg [63:0] mtimecmp_q;
    reg        msip_q;

    wire [9:0]  idx   = addr[11:2];
    wire        wr    = req && we;
    wire [31:0] wmask = {{8{be[3]}}, {8{be[2]}}, {8{be[1]}}, {8{be[0]}}};

    function [31:0] merge(input [31:0] old, input [31:0] new_val, input [31:0] mask);
        merge = (old & ~mask) | (new_val & mask);
    endfunction

    always @(posedge clk) begin
        if (rst) begin
            mtime_q    <= 64'd0;
            mtimecmp_q <= {`TL_TIMER_MTIMECMP_HI_RESET, `TL_TIMER_MTIMECMP_LO_RESET};
            msip_q     <= `TL_TIMER_MSIP_MSIP_RESET;
        end else begin
            // A write to mtime replaces the count for this cycle (no increment).
            if (wr && idx == `TL_TIMER_MTIME_LO_IDX)
                mtime_q <= {mtime_q[63:32], merge(mtime_q[31:0], wdata, wmask)};
            else if (wr && idx == `TL_TIMER_MTIME_HI_IDX)
                mtime_q <= {merge(mtime_q[63:32], wdata, wmask), mtime_q[31:0]};
            else
                mtime_q <= mtime_q + 64'd1;
            if (wr && idx == `TL_TIMER_MTIMECMP_LO_IDX)
                mtimecmp_q[31:0] <= merge(mtimecmp_q[31:0], wdata, wmask);
            if (wr && idx == `TL_TIMER_MTIMECMP_HI_IDX)
                mtimecmp_q[63:32] <= merge(mtimecmp_q[63:32], wdata, wmask);
            if (wr && idx == `TL_TIMER_MSIP_IDX && be[0])
                msip_q <= wdata[`TL_TIMER_MSIP_MSIP_LSB];
        end
    end

    // Bus response: one cycle after the request strobe.
    always @(posedge clk) begin
        if (rst) begin
            ack   <= 1'b0;
            err   <= 1'b0;
            rdata <= 32'd0;
        end else begin
            ack   <= req;
            err   <= 1'b0;
            rdata <= 32'd0;
            if (req) begin
                case (idx)
                    `TL_TIMER_MTIME_LO_IDX:    rdata <= mtime_q[31:0];
                    `TL_TIMER_MTIME_HI_IDX:    rdata <= mtime_q[63:32];
                    `TL_TIMER_MTIMECMP_LO_IDX: rdata <= mtimecmp_q[31:0];
                    `TL_TIMER_MTIMECMP_HI_IDX: rdata <= mtimecmp_q[63:32];
                    `TL_TIMER_MSIP_IDX:        rdata <= {31'd0, msip_q};
                    default:                   err   <= 1'b1;
                endcase
            end
        end
    end

    assign mtime        = mtime_q;
    assign irq_timer    = (mtime_q >= mtimecmp_q);
    assign irq_software = msip_q;

endmodule

`default_nettype wire
