// SPDX-License-Identifier: MIT
// tl_soc_intc: interrupt controller for the peripherals -> the CPU's irq_external.
//
// Sources are pulses or levels; a rising edge sets the source's PENDING bit,
// so a one-cycle event (PWM period start, encoder index) is never lost while
// the CPU is busy.  PENDING is write-1-to-clear; an event in the same cycle
// as the clear wins, so clearing cannot swallow a new event.  irq_external
// is the level |(PENDING & ENABLE).  Bit layout: INTC block of
// torqueloop/spec/regmap.toml.  Bus slave: see tl_soc_timer.v.
// the register map's TL_* names (generated; the include guard makes a second include empty)
`include "regmap.vh"
`include "tl_soc_page.vh"
`default_nettype none

module tl_soc_intc #(
    parameter integer N_SRC = `TL_INTC_ENABLE_MASK_WIDTH   // sources, fixed by the register map
) (
    input  wire             clk,
    input  wire             rst,
    input  wire [N_SRC-1:0] src,
    output wire             irq_external,
    // bus (docs/soc.md, Bus; tl_soc_page.vh)
    /* verilator lint_off UNUSEDSIGNAL */  // a block reads the bits of the bundle it needs
    `SOC_PAGE_PORTS
    /* verilator lint_on UNUSEDSIGNAL */
);

    localparam [31:0] PENDING_RESET = `TL_INTC_PENDING_RESET;
    localparam [31:0] ENABLE_RESET  = `TL_INTC_ENABLE_RESET;

    `SOC_PAGE_RSP         // rdata, err: the read decode at the end

    reg [N_SRC-1:0] src_q;
    reg [N_SRC-1:0] pending;
    reg [N_SRC-1:0] enable;

    wire             wr    = bus_req[`TL_BUS_REQ_STB_LSB] && bus_req[`TL_BUS_REQ_WE_LSB];
    wire [9:0]       idx   = bus_req[`TL_BUS_REQ_IDX_MSB:`TL_BUS_REQ_IDX_LSB];
    wire [N_SRC-1:0] wmask = bus_req[`TL_BUS_REQ_WMASK_LSB +: N_SRC];
    wire [N_SRC-1:0] wbits = bus_req[`TL_BUS_REQ_WBITS_LSB +: N_SRC];
    wire [N_SRC-1:0] rise  = src & ~src_q;
    wire [N_SRC-1:0] clr   = (wr && idx == `TL_INTC_PENDING_IDX) ? wbits : {N_SRC{1'b0}};
    wire [N_SRC-1:0] set   = (wr && idx == `TL_INTC_SET_IDX)     ? wbits : {N_SRC{1'b0}};
    wire [N_SRC-1:0] active = pending & enable;

    always @(posedge clk) begin
        if (rst) begin
            // Levels already high at reset release count as edges: src_q = 0.
            src_q   <= {N_SRC{1'b0}};
            pending <= PENDING_RESET[N_SRC-1:0];
            enable  <= ENABLE_RESET[N_SRC-1:0];
        end else begin
            src_q   <= src;
            pending <= (pending & ~clr) | rise | set;
            if (wr && idx == `TL_INTC_ENABLE_IDX)
                enable <= (enable & ~wmask) | wbits;
        end
    end

    // Read decode: this block's registers only; tl_soc_fabric acknowledges.
    always @(*) begin
        {err, rdata} = 33'd0;
        case (idx)
            `TL_INTC_PENDING_IDX: rdata[N_SRC-1:0] = pending;
            `TL_INTC_ENABLE_IDX:  rdata[N_SRC-1:0] = enable;
            `TL_INTC_ACTIVE_IDX:  rdata[N_SRC-1:0] = active;
            `TL_INTC_SET_IDX:     rdata = 32'd0;
            default:              err = 1'b1;
        endcase
    end

    assign irq_external = |active;

endmodule

`default_nettype wire
