// SPDX-License-Identifier: MIT
// soc_flash: the configuration flash's serial port (FLASH block of
// torqueloop/spec/regmap.toml): chip select, and one byte at a time each way,
// MSB first, SPI mode 0 - DCLK idles low, the flash samples ASDO on its
// rising edge and changes DATA0 after its falling edge, this block samples
// DATA0 on the rising edge.  DCLK = clk / (2 * HALF_CLKS): 12.5 MHz at 50 MHz,
// under the EPCS's 20 MHz READ limit.  The firmware speaks the EPCS command
// set through it (firmware/servo/store.c); on the DE0-CV the pins reach the
// EPCS64 through the Cyclone V's ASMI block (docs/soc.md, "Configuration flash").
//
// flash_miso is not synchronised: it is driven by the flash in step with our
// own DCLK and is stable for a whole half period (80 ns, against the EPCS's
// 8 ns clock-to-output) when it is sampled - not an asynchronous input.
// Bus slave: see tl_soc_timer.v.
// the register map's TL_* names (generated; the include guard makes a second include empty)
`include "regmap.vh"
`include "tl_soc_page.vh"
`default_nettype none

module tl_soc_flash #(
    parameter integer HALF_CLKS = 2        // clocks per DCLK half period
) (
    input  wire        clk,
    input  wire        rst,
    output wire        flash_dclk,
    output wire        flash_ncs,          // active low
    output wire        flash_mosi,         // to the flash (ASDO)
    input  wire        flash_miso,         // from the flash (DATA0)
    // bus (docs/soc.md, Bus; tl_soc_page.vh)
    /* verilator lint_off UNUSEDSIGNAL */  // a block reads the bits of the bundle it needs
    `SOC_PAGE_PORTS
    /* verilator lint_on UNUSEDSIGNAL */
);

    localparam integer DW = (HALF_CLKS > 1) ? $clog2(HALF_CLKS) : 1;

    `SOC_PAGE_RSP         // rdata, err: the read decode at the end

    wire        wr    = bus_req[`TL_BUS_REQ_STB_LSB] && bus_req[`TL_BUS_REQ_WE_LSB];
    wire [9:0]  idx   = bus_req[`TL_BUS_REQ_IDX_MSB:`TL_BUS_REQ_IDX_LSB];
    wire        lane0 = bus_req[`TL_BUS_REQ_WMASK_LSB];          // byte lane 0 written: every register is in it
    wire [7:0]  wbyte = bus_req[`TL_BUS_REQ_WBITS_LSB +: 8];

    reg          cs_q;
    reg          busy;
    reg          dclk_q;
    reg [DW-1:0] div;
    reg [2:0]    bits;          // bits left after the current one, on its falling edge
    reg [7:0]    tx_sh;         // MSB on the line
    reg [7:0]    rx_sh;
    reg [7:0]    rx_q;

    wire start = wr && idx == `TL_FLASH_TX_IDX && lane0 && !busy;
    wire tick  = busy && div == HALF_CLKS[DW-1:0] - 1'b1;

    always @(posedge clk) begin
        if (rst) begin
            cs_q   <= 1'b0;
            busy   <= 1'b0;
            dclk_q <= 1'b0;
            div    <= {DW{1'b0}};
            bits   <= 3'd0;
            tx_sh  <= 8'd0;
            rx_sh  <= 8'd0;
            rx_q   <= 8'd0;
        end else begin
            if (wr && idx == `TL_FLASH_CTRL_IDX && lane0)
                cs_q <= wbyte[`TL_FLASH_CTRL_CS_LSB];
            if (start) begin
                busy  <= 1'b1;
                div   <= {DW{1'b0}};
                bits  <= 3'd7;
                tx_sh <= wbyte;
            end else if (busy) begin
                div <= tick ? {DW{1'b0}} : div + 1'b1;
                if (tick && !dclk_q) begin
                    dclk_q <= 1'b1;                        // rising: both sides sample
                    rx_sh  <= {rx_sh[6:0], flash_miso};
                end else if (tick) begin
                    dclk_q <= 1'b0;                        // falling: the next bit goes out
                    tx_sh  <= {tx_sh[6:0], 1'b0};
                    bits   <= bits - 1'b1;
                    if (bits == 3'd0) begin
                        busy <= 1'b0;
                        rx_q <= rx_sh;
                    end
                end
            end
        end
    end

    // Read decode: this block's registers only; tl_soc_fabric acknowledges.
    always @(*) begin
        {err, rdata} = 33'd0;
        case (idx)
            `TL_FLASH_CTRL_IDX: rdata[`TL_FLASH_CTRL_CS_LSB] = cs_q;
            `TL_FLASH_TX_IDX:   rdata = 32'd0;
            `TL_FLASH_RX_IDX: begin
                rdata[`TL_FLASH_RX_DATA_MSB:`TL_FLASH_RX_DATA_LSB] = rx_q;
                rdata[`TL_FLASH_RX_BUSY_LSB] = busy;
            end
            default:            err = 1'b1;
        endcase
    end

    assign flash_dclk = dclk_q;
    assign flash_ncs  = !cs_q;
    assign flash_mosi = tx_sh[7];

endmodule

`default_nettype wire
