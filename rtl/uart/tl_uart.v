// SPDX-License-Identifier: MIT
// tl_uart: the RN-XV link - 8N1 receiver and transmitter with FIFOs, run-time
// baud divisor, overrun counting and optional RTS/CTS flow control.
//
//   rxd --> uart_rx --> rx FIFO --> m_rx_*      (firmware reads)
//   s_tx_* --> tx FIFO --> uart_tx --> txd      (firmware writes)
//
// Baud rate: one bit lasts baud_div + 1 clocks.  baud_div = 0 selects the
// reset default DEFAULT_BAUD (115200 at CLK_HZ = 50 MHz: 434 clocks per bit,
// 115207 baud, +0.006 %), so a register block that resets to 0 gives a
// working link.  Values 1-14 are raised to 15 (16 clocks per bit: the
// receiver's three sample points need L >= 16).
//
// Flow control (flow_en = 1): the transmitter starts a byte only while the
// peer asserts cts_n low; rts_n goes high (stop sending) when the RX FIFO
// holds FIFO_DEPTH - RTS_SLACK bytes or more, leaving RTS_SLACK bytes of room
// for what the peer has in flight.  With flow_en = 0, cts_n is ignored and
// rts_n is held low.
//
// Errors: frame_error and break_detect come from uart_rx (one-clock pulses;
// a break also pulses frame_error; the byte of a bad frame is dropped);
// overrun_error pulses when a good byte arrives to a full RX FIFO - the byte
// is dropped and overrun_count (saturating) counts it until overrun_clear.
`default_nettype none

module tl_uart #(
    parameter integer CLK_HZ       = 50_000_000,
    parameter integer DEFAULT_BAUD = 115_200,
    parameter integer FIFO_DEPTH   = 16,   // each FIFO, power of two >= 2
    parameter integer RTS_SLACK    = 4     // free RX entries left when rts_n rises, 1..FIFO_DEPTH
) (
    input  wire                         clk,
    input  wire                         rst,            // synchronous, active high
    // settings
    input  wire [15:0]                  baud_div,       // clocks per bit - 1; 0 = DEFAULT_BAUD
    input  wire                         flow_en,        // RTS/CTS on
    // transmit stream (into the TX FIFO)
    input  wire [7:0]                   s_tx_data,
    input  wire                         s_tx_valid,
    output wire                         s_tx_ready,
    // receive stream (out of the RX FIFO)
    output wire [7:0]                   m_rx_data,
    output wire                         m_rx_valid,
    input  wire                         m_rx_ready,
    // status
    output wire [$clog2(FIFO_DEPTH):0]  rx_level,
    output wire [$clog2(FIFO_DEPTH):0]  tx_level,
    output wire                         tx_busy,        // a frame is on txd
    output wire                         frame_error,
    output wire                         break_detect,
    output reg                          overrun_error,
    output reg  [15:0]                  overrun_count,
    input  wire                         overrun_clear,
    // pins
    input  wire                         rxd,            // asynchronous
    output wire                         txd,
    input  wire                         cts_n,          // asynchronous, low = peer ready
    output reg                          rts_n           // low = we can take more
);

    localparam integer DEFAULT_DIV = (CLK_HZ + DEFAULT_BAUD / 2) / DEFAULT_BAUD - 1;
    localparam [15:0]  MIN_DIV     = 16'd15;
    localparam integer LW          = $clog2(FIFO_DEPTH) + 1;
    localparam integer RTS_LEVEL_I = FIFO_DEPTH - RTS_SLACK;
    localparam [LW-1:0] RTS_LEVEL  = RTS_LEVEL_I[LW-1:0];

    wire [15:0] div = (baud_div == 16'd0) ? DEFAULT_DIV[15:0]
                    : (baud_div < MIN_DIV) ? MIN_DIV : baud_div;

    // --- receive ----------------------------------------------------------------------
    wire [7:0] rx_data;
    wire       rx_valid;
    wire       rx_fifo_ready;

    tl_uart_rx u_rx (
        .clk(clk), .rst(rst), .baud_div(div), .rxd(rxd),
        .m_data(rx_data), .m_valid(rx_valid),
        .frame_error(frame_error), .break_detect(break_detect)
    );

    tl_sync_fifo #(.WIDTH(8), .DEPTH(FIFO_DEPTH)) u_rx_fifo (
        .clk(clk), .rst(rst),
        .s_data(rx_data), .s_valid(rx_valid), .s_ready(rx_fifo_ready),
        .m_data(m_rx_data), .m_valid(m_rx_valid), .m_ready(m_rx_ready),
        .level(rx_level)
    );

    wire overrun = rx_valid && !rx_fifo_ready;

    always @(posedge clk) begin
        if (rst) begin
            overrun_error <= 1'b0;
            overrun_count <= 16'd0;
            rts_n         <= 1'b0;
        end else begin
            overrun_error <= overrun;
            // an overrun in the clearing clock is kept: it happened after the read
            if (overrun)
                overrun_count <= overrun_clear ? 16'd1
                               : (overrun_count == 16'hffff) ? overrun_count : overrun_count + 16'd1;
            else if (overrun_clear)
                overrun_count <= 16'd0;
            rts_n <= flow_en && (rx_level >= RTS_LEVEL);
        end
    end

    // --- transmit ----------------------------------------------------------------------
    wire       cts_n_sync;
    wire [7:0] tx_data;
    wire       tx_valid;
    wire       tx_ready;

    tl_sync_2ff #(.WIDTH(1), .RESET_VAL(1)) u_cts_sync (
        .clk(clk), .rst(rst), .async_in(cts_n), .sync_out(cts_n_sync)
    );

    tl_sync_fifo #(.WIDTH(8), .DEPTH(FIFO_DEPTH)) u_tx_fifo (
        .clk(clk), .rst(rst),
        .s_data(s_tx_data), .s_valid(s_tx_valid), .s_ready(s_tx_ready),
        .m_data(tx_data), .m_valid(tx_valid), .m_ready(tx_ready),
        .level(tx_level)
    );

    tl_uart_tx u_tx (
        .clk(clk), .rst(rst), .baud_div(div),
        .s_data(tx_data), .s_valid(tx_valid), .s_ready(tx_ready),
        .cts_ok(!flow_en || !cts_n_sync), .txd(txd), .busy(tx_busy)
    );

endmodule

`default_nettype wire
