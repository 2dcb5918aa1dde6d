// SPDX-License-Identifier: MIT
// tl_soc_uart: the RN-XV WiFi link (paper section V.A) as a register page
// (UART layout of torqueloop/spec/regmap.toml) around rtl/uart/tl_uart.
//
// The core does the line work; this block moves bytes between the bus and
// its FIFOs, holds the baud divisor and flow-control switch, turns the
// core's one-clock error pulses into sticky flags, and counts frame errors
// (the core counts overruns).  A read of RX_DATA pops the byte it returns,
// in the same clock, so each byte is seen exactly once.
// Bus slave: see tl_soc_timer.v.
// the register map's TL_* names (generated; the include guard makes a second include empty)
`include "regmap.vh"
`include "tl_soc_page.vh"
`default_nettype none

module tl_soc_uart #(
    parameter integer CLK_HZ     = 50_000_000,
    parameter integer FIFO_DEPTH = 16
) (
    input  wire        clk,
    input  wire        rst,
    // pins
    input  wire        rxd,           // asynchronous (the core synchronises)
    output wire        txd,
    input  wire        cts_n,         // asynchronous
    output wire        rts_n,
    // interrupt sources (levels; the INTC latches their rising edges)
    output wire        rx_event,      // RX FIFO not empty
    output wire        tx_event,      // TX FIFO empty
    // bus (docs/soc.md, Bus; tl_soc_page.vh)
    /* verilator lint_off UNUSEDSIGNAL */  // a block reads the bits of the bundle it needs
    `SOC_PAGE_PORTS
    /* verilator lint_on UNUSEDSIGNAL */
);

    localparam integer LVL_BITS = $clog2(FIFO_DEPTH) + 1;
    localparam [31:0]  BAUD_RESET = `TL_UART_BAUD_DIV_RESET;
    localparam [31:0]  CTRL_RESET = `TL_UART_CTRL_RESET;

    `SOC_PAGE_RSP         // rdata, err: the read decode at the end

    wire        stb   = bus_req[`TL_BUS_REQ_STB_LSB];
    wire        wr    = stb && bus_req[`TL_BUS_REQ_WE_LSB];
    wire        rd    = stb && !bus_req[`TL_BUS_REQ_WE_LSB];
    wire [9:0]  idx   = bus_req[`TL_BUS_REQ_IDX_MSB:`TL_BUS_REQ_IDX_LSB];
    wire [15:0] wmask = bus_req[`TL_BUS_REQ_WMASK_LSB +: 16];
    wire [15:0] wbits = bus_req[`TL_BUS_REQ_WBITS_LSB +: 16];

    reg [15:0] baud_q;
    reg        flow_q;
    reg [3:0]  err_q;          // {tx_drop, overrun, break, frame}, as ERR[3:0]
    reg [15:0] frame_count;

    wire [7:0]          rx_data;
    wire                rx_valid, tx_ready, tx_busy;
    wire [LVL_BITS-1:0] rx_level, tx_level;
    wire                frame_error, break_detect, overrun_error;
    wire [15:0]         overrun_count;

    wire tx_push   = wr && idx == `TL_UART_TX_DATA_IDX && wmask[0];
    wire rx_pop    = rd && idx == `TL_UART_RX_DATA_IDX;
    wire cnt_clr   = wr && idx == `TL_UART_CNT_CLEAR_IDX;
    wire err_wr    = wr && idx == `TL_UART_ERR_IDX;

    tl_uart #(.CLK_HZ(CLK_HZ), .FIFO_DEPTH(FIFO_DEPTH)) u_uart (
        .clk(clk), .rst(rst), .baud_div(baud_q), .flow_en(flow_q),
        .s_tx_data(wbits[7:0]), .s_tx_valid(tx_push), .s_tx_ready(tx_ready),
        .m_rx_data(rx_data), .m_rx_valid(rx_valid), .m_rx_ready(rx_pop),
        .rx_level(rx_level), .tx_level(tx_level), .tx_busy(tx_busy),
        .frame_error(frame_error), .break_detect(break_detect),
        .overrun_error(overrun_error), .overrun_count(overrun_count),
        .overrun_clear(cnt_clr && wbits[`TL_UART_CNT_CLEAR_OVERRUN_LSB]),
        .rxd(rxd), .txd(txd), .cts_n(cts_n), .rts_n(rts_n)
    );

    wire [3:0] err_set = {tx_push && !tx_ready, overrun_error, break_detect, frame_error};
    wire [3:0] err_clr = err_wr ? wbits[`TL_UART_ERR_TX_DROP_LSB:`TL_UART_ERR_FRAME_LSB] : 4'd0;

    always @(posedge clk) begin
        if (rst) begin
            baud_q      <= BAUD_RESET[15:0];
            flow_q      <= CTRL_RESET[`TL_UART_CTRL_FLOW_EN_LSB];
            err_q       <= 4'd0;
            frame_count <= 16'd0;
        end else begin
            if (wr && idx == `TL_UART_BAUD_DIV_IDX)
                baud_q <= (baud_q & ~wmask) | wbits;
            if (wr && idx == `TL_UART_CTRL_IDX && wmask[`TL_UART_CTRL_FLOW_EN_LSB])
                flow_q <= wbits[`TL_UART_CTRL_FLOW_EN_LSB];
            // A new error in the clearing clock stays set.
            err_q <= (err_q & ~err_clr) | err_set;
            if (cnt_clr && wbits[`TL_UART_CNT_CLEAR_FRAME_LSB])
                frame_count <= frame_error ? 16'd1 : 16'd0;
            else if (frame_error && frame_count != 16'hFFFF)
                frame_count <= frame_count + 16'd1;
        end
    end

    wire tx_idle = !tx_busy && (tx_level == {LVL_BITS{1'b0}});

    // Read decode: this block's registers only; tl_soc_fabric acknowledges.
    always @(*) begin
        {err, rdata} = 33'd0;
        case (idx)
            `TL_UART_TX_DATA_IDX:  rdata = 32'd0;
            `TL_UART_RX_DATA_IDX: begin
                rdata[`TL_UART_RX_DATA_DATA_MSB:`TL_UART_RX_DATA_DATA_LSB] = rx_valid ? rx_data : 8'd0;
                rdata[`TL_UART_RX_DATA_VALID_LSB] = rx_valid;
            end
            `TL_UART_STATUS_IDX: begin
                rdata[`TL_UART_STATUS_TX_READY_LSB] = tx_ready;
                rdata[`TL_UART_STATUS_TX_IDLE_LSB]  = tx_idle;
                rdata[`TL_UART_STATUS_RX_VALID_LSB] = rx_valid;
                rdata[`TL_UART_STATUS_RTS_N_LSB]    = rts_n;
                rdata[`TL_UART_STATUS_RX_LEVEL_LSB +: LVL_BITS] = rx_level;
                rdata[`TL_UART_STATUS_TX_LEVEL_LSB +: LVL_BITS] = tx_level;
            end
            `TL_UART_BAUD_DIV_IDX:      rdata[15:0] = baud_q;
            `TL_UART_CTRL_IDX:          rdata[`TL_UART_CTRL_FLOW_EN_LSB] = flow_q;
            `TL_UART_ERR_IDX:           rdata[3:0]  = err_q;
            `TL_UART_FRAME_COUNT_IDX:   rdata[15:0] = frame_count;
            `TL_UART_OVERRUN_COUNT_IDX: rdata[15:0] = overrun_count;
            `TL_UART_CNT_CLEAR_IDX:     rdata = 32'd0;
            default:                    err = 1'b1;
        endcase
    end

    assign rx_event = rx_valid;
    assign tx_event = tx_idle;

endmodule

`default_nettype wire
