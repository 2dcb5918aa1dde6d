// SPDX-License-Identifier: MIT
// tl_soc_gpio: the DE0-CV's LEDs, slide switches, push buttons and six
// 7-segment digits as registers (GPIO block of torqueloop/spec/regmap.toml).
//
// SW and KEY are asynchronous to the clock and enter through sync_2ff.  The
// board's KEY and HEX signals are active low (see /work/shared/board); the
// inversion happens here so software sees 1 = pressed / lit.  A key press
// (0->1 after synchronisation) sets KEY_EDGE and pulses key_event for the
// interrupt controller.  No debouncing: software that cares waits ~20 ms.
// Bus slave: see tl_soc_timer.v.
// the register map's TL_* names (generated; the include guard makes a second include empty)
`include "regmap.vh"
`include "tl_soc_page.vh"
`default_nettype none

module tl_soc_gpio (
    input  wire        clk,
    input  wire        rst,
    // board pins
    output wire [9:0]  ledr,
    input  wire [9:0]  sw,        // asynchronous
    input  wire [3:0]  key_n,     // asynchronous, active low
    output wire [6:0]  hex0_n,    // segment a = bit 0 ... g = bit 6, active low
    output wire [6:0]  hex1_n,
    output wire [6:0]  hex2_n,
    output wire [6:0]  hex3_n,
    output wire [6:0]  hex4_n,
    output wire [6:0]  hex5_n,
    output wire        key_event, // one-cycle pulse: a key was pressed
    // bus (docs/soc.md, Bus; tl_soc_page.vh)
    /* verilator lint_off UNUSEDSIGNAL */  // a block reads the bits of the bundle it needs
    `SOC_PAGE_PORTS
    /* verilator lint_on UNUSEDSIGNAL */
);

    localparam [31:0] LEDR_RESET   = `TL_GPIO_LEDR_RESET;
    localparam [31:0] HEX_LO_RESET = `TL_GPIO_HEX_LO_RESET;
    localparam [31:0] HEX_HI_RESET = `TL_GPIO_HEX_HI_RESET;

    `SOC_PAGE_RSP         // rdata, err: the read decode at the end

    wire [9:0] sw_s;
    wire [3:0] key_n_s;

    // Idle levels as reset values: switches read 0, released keys read 1 (low active).
    tl_sync_2ff #(.WIDTH(10), .RESET_VAL(0)) u_sync_sw  (.clk(clk), .rst(rst), .async_in(sw),    .sync_out(sw_s));
    tl_sync_2ff #(.WIDTH(4),  .RESET_VAL(1)) u_sync_key (.clk(clk), .rst(rst), .async_in(key_n), .sync_out(key_n_s));

    wire [3:0] key = ~key_n_s;

    reg [9:0]  ledr_q;
    reg [31:0] hex_lo_q;
    reg [31:0] hex_hi_q;
    reg [3:0]  key_q;
    reg [3:0]  key_edge;
    reg        key_event_q;

    `SOC_PAGE_WRITE       // wr, idx, wmask, wbits
    wire [3:0]  press = key & ~key_q;
    wire [3:0]  clr   = (wr && idx == `TL_GPIO_KEY_EDGE_IDX) ? wbits[3:0] : 4'd0;

    always @(posedge clk) begin
        if (rst) begin
            ledr_q      <= LEDR_RESET[9:0];
            hex_lo_q    <= HEX_LO_RESET;
            hex_hi_q    <= HEX_HI_RESET;
            key_q       <= 4'd0;
            key_edge    <= 4'd0;
            key_event_q <= 1'b0;
        end else begin
            key_q       <= key;
            // A press in the same cycle as the clear wins.
            key_edge    <= (key_edge & ~clr) | press;
            key_event_q <= |press;
            if (wr && idx == `TL_GPIO_LEDR_IDX)
                ledr_q <= (ledr_q & ~wmask[9:0]) | wbits[9:0];
            if (wr && idx == `TL_GPIO_HEX_LO_IDX)
                hex_lo_q <= ((hex_lo_q & ~wmask) | wbits) & `TL_GPIO_HEX_LO_RW_MASK;
            if (wr && idx == `TL_GPIO_HEX_HI_IDX)
                hex_hi_q <= ((hex_hi_q & ~wmask) | wbits) & `TL_GPIO_HEX_HI_RW_MASK;
        end
    end

    // Read decode: this block's registers only; tl_soc_fabric acknowledges.
    always @(*) begin
        {err, rdata} = 33'd0;
        case (idx)
            `TL_GPIO_LEDR_IDX:     rdata[9:0] = ledr_q;
            `TL_GPIO_SW_IDX:       rdata[9:0] = sw_s;
            `TL_GPIO_KEY_IDX:      rdata[3:0] = key;
            `TL_GPIO_KEY_EDGE_IDX: rdata[3:0] = key_edge;
            `TL_GPIO_HEX_LO_IDX:   rdata      = hex_lo_q;
            `TL_GPIO_HEX_HI_IDX:   rdata      = hex_hi_q;
            default:               err        = 1'b1;
        endcase
    end

    assign ledr      = ledr_q;
    assign hex0_n    = ~hex_lo_q[`TL_GPIO_HEX_LO_HEX0_MSB:`TL_GPIO_HEX_LO_HEX0_LSB];
    assign hex1_n    = ~hex_lo_q[`TL_GPIO_HEX_LO_HEX1_MSB:`TL_GPIO_HEX_LO_HEX1_LSB];
    assign hex2_n    = ~hex_lo_q[`TL_GPIO_HEX_LO_HEX2_MSB:`TL_GPIO_HEX_LO_HEX2_LSB];
    assign hex3_n    = ~hex_lo_q[`TL_GPIO_HEX_LO_HEX3_MSB:`TL_GPIO_HEX_LO_HEX3_LSB];
    assign hex4_n    = ~hex_hi_q[`TL_GPIO_HEX_HI_HEX4_MSB:`TL_GPIO_HEX_HI_HEX4_LSB];
    assign hex5_n    = ~hex_hi_q[`TL_GPIO_HEX_HI_HEX5_MSB:`TL_GPIO_HEX_HI_HEX5_LSB];
    assign key_event = key_event_q;

endmodule

`default_nettype wire
