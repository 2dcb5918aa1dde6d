// SPDX-License-Identifier: MIT
// tl_soc_timer: RISC-V machine timer (mtime, mtimecmp) and software interrupt (msip).
//
// mtime counts clock cycles (CLOCK_50: 20 ns), so control-loop periods and
// encoder timestamps share one time base.  irq_timer is the level
// mtime >= mtimecmp, as the privileged spec defines it; mtimecmp resets to
// all ones so no interrupt fires before firmware arms it.  Register layout:
// TIMER block of torqueloop/spec/regmap.toml.  Bus slave as every block of
// the SoC: a request bundle in, the read value and decode error out, in the
// same cycle; tl_soc_fabric acknowledges (docs/soc.md, Bus).
// the register map's TL_* names (generated; the include guard makes a second include empty)
`include "regmap.vh"
`include "tl_soc_page.vh"
`default_nettype none

module tl_soc_timer (
    input  wire        clk,
    input  wire        rst,
    output wire [63:0] mtime,
    output wire        irq_timer,
    output wire        irq_software,
    // bus (docs/soc.md, Bus; tl_soc_page.vh)
    `SOC_PAGE_PORTS
);

    `SOC_PAGE_RSP         // rdata, err: the read decode at the end

    reg [63:0] mtime_q;
    reg [63:0] mtimecmp_q;
    reg        msip_q;

    `SOC_PAGE_WRITE       // wr, idx, wmask, wbits

    function [31:0] merge(input [31:0] old, input [31:0] mask, input [31:0] bits);
        merge = (old & ~mask) | bits;
    endfunction

    always @(posedge clk) begin
        if (rst) begin
            mtime_q    <= 64'd0;
            mtimecmp_q <= {`TL_TIMER_MTIMECMP_HI_RESET, `TL_TIMER_MTIMECMP_LO_RESET};
            msip_q     <= `TL_TIMER_MSIP_MSIP_RESET;
        end else begin
            // A write to mtime replaces the count for this cycle (no increment).
            if (wr && idx == `TL_TIMER_MTIME_LO_IDX)
                mtime_q <= {mtime_q[63:32], merge(mtime_q[31:0], wmask, wbits)};
            else if (wr && idx == `TL_TIMER_MTIME_HI_IDX)
                mtime_q <= {merge(mtime_q[63:32], wmask, wbits), mtime_q[31:0]};
            else
                mtime_q <= mtime_q + 64'd1;
            if (wr && idx == `TL_TIMER_MTIMECMP_LO_IDX)
                mtimecmp_q[31:0] <= merge(mtimecmp_q[31:0], wmask, wbits);
            if (wr && idx == `TL_TIMER_MTIMECMP_HI_IDX)
                mtimecmp_q[63:32] <= merge(mtimecmp_q[63:32], wmask, wbits);
            if (wr && idx == `TL_TIMER_MSIP_IDX && wmask[`TL_TIMER_MSIP_MSIP_LSB])
                msip_q <= wbits[`TL_TIMER_MSIP_MSIP_LSB];
        end
    end

    // Read decode: this block's registers only; tl_soc_fabric acknowledges.
    always @(*) begin
        {err, rdata} = 33'd0;
        case (idx)
            `TL_TIMER_MTIME_LO_IDX:    rdata = mtime_q[31:0];
            `TL_TIMER_MTIME_HI_IDX:    rdata = mtime_q[63:32];
            `TL_TIMER_MTIMECMP_LO_IDX: rdata = mtimecmp_q[31:0];
            `TL_TIMER_MTIMECMP_HI_IDX: rdata = mtimecmp_q[63:32];
            `TL_TIMER_MSIP_IDX:        rdata = {31'd0, msip_q};
            default:                   err   = 1'b1;
        endcase
    end

    assign mtime        = mtime_q;
    assign irq_timer    = (mtime_q >= mtimecmp_q);
    assign irq_software = msip_q;

endmodule

`default_nettype wire
