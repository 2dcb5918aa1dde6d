// SPDX-License-Identifier: MIT
// soc_intc: interrupt controller for the peripherals -> the CPU's irq_external.
//
// Sources are pulses or levels; a rising edge sets the source's PENDING bit,
// so a one-cycle event (PWM period start, encoder index) is never lost while
// the CPU is busy.  PENDING is write-1-to-clear; an event in the same cycle
// as the clear wins, so clearing cannot swallow a new event.  irq_external
// is the level |(PENDING & ENABLE).  Bit layout: INTC block of
// torqueloop/spec/regmap.toml.  Slave contract as in soc_ram.v.
`default_nettype none

module tl_soc_intc #(
    parameter integer N_SRC = `TL_INTC_ENABLE_MASK_WIDTH   // sources, fixed by the register map
) (
    input  wire             clk,
    input  wire             rst,
    input  wire             req,
    input  wire             we,
    input  wire [3:0]       be,
    /* verilator lint_off UNUSEDSIGNAL */  // addr[1:0]: byte lanes come from be
    input  wire [11:0]      addr,
    /* verilator lint_on UNUSEDSIGNAL */
    input  wire [31:0]      wdata,
    output reg              ack,
    output reg              err,
    output reg  [31:0]      rdata,
    input  wire [N_SRC-1:0] src,
    output wire             irq_external
);

    localparam [31:0] PENDING_RESET = `TL_INTC_PENDING_RESET;
    localparam [31:0] ENABLE_RESET  = `TL_INTC_ENABLE_RESET;

    reg [N_SRC-1:0] src_q;
    reg [N_SRC-1:0] pending;
    reg [N_SRC-1:0] enable;

    wire [9:0]       idx   = addr[11:2];
    wire             wr    = req && we;
    wire [31:0]      wmask = {{8{be[3]}}, {8{be[2]}}, {8{be[1]}}, {8{be[0]}}};
    /* verilator lint_off UNUSEDSIGNAL */
    wire [31:0]      wbits = wdata & wmask;
    /* verilator lint_on UNUSEDSIGNAL */
    wire [N_SRC-1:0] rise  = src & ~src_q;
    wire [N_SRC-1:0] clr   = (wr && idx == `TL_INTC_PENDING_IDX) ? wbits[N_SRC-1:0] : {N_SRC{1'b0}};
    wire [N_SRC-1:0] set   = (wr && idx == `TL_INTC_SET_IDX)     ? wbits[N_SRC-1:0] : {N_SRC{1'b0}};
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
                enable <= (enable & ~wmask[N_SRC-1:0]) | wbits[N_SRC-1:0];
        end
    end

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
                    `TL_INTC_PENDING_IDX: rdata[N_SRC-1:0] <= pending;
                    `TL_INTC_ENABLE_IDX:  rdata[N_SRC-1:0] <= enable;
                    `TL_INTC_ACTIVE_IDX:  rdata[N_SRC-1:0] <= active;
                    `TL_INTC_SET_IDX:     rdata <= 32'd0;
                    default:              err <= 1'b1;
                endcase
            end
        end
    end

    assign irq_external = |active;

endmodule

`default_nettype wire
