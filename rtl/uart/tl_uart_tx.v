// SPDX-License-Identifier: MIT
// tl_uart_tx: 8N1 transmitter with a run-time bit period.
//
// One bit lasts baud_div + 1 clocks (baud = CLK_HZ / (baud_div + 1)); a new
// value of baud_div takes effect at the next bit boundary.  A byte is taken
// from the valid/ready input only between frames and only while cts_ok is
// high, so flow control (RTS/CTS, in rtl/uart/tl_uart.v) never cuts a frame:
// a byte already started is always finished.  Back-to-back bytes follow
// each other with no idle time after the one stop bit.
`default_nettype none

module tl_uart_tx (
    input  wire        clk,
    input  wire        rst,        // synchronous, active high
    input  wire [15:0] baud_div,   // clocks per bit - 1
    input  wire [7:0]  s_data,
    input  wire        s_valid,
    output wire        s_ready,
    input  wire        cts_ok,     // peer may receive: start a new frame only when high
    output wire        txd,        // idle high
    output wire        busy        // a frame is on the line
);

    reg [9:0]  shift;       // bits still to send, LSB on the line: {stop, data, start}
    reg [3:0]  bits_left;   // 0 = idle
    reg [15:0] clk_cnt;     // clocks left in the current bit

    assign busy    = (bits_left != 4'd0);
    assign s_ready = !busy && cts_ok;
    assign txd     = shift[0];

    always @(posedge clk) begin
        if (rst) begin
            shift     <= 10'h3ff;
            bits_left <= 4'd0;
            clk_cnt   <= 16'd0;
        end else if (!busy) begin
            if (s_valid && cts_ok) begin
                shift     <= {1'b1, s_data, 1'b0};
                bits_left <= 4'd10;
                clk_cnt   <= baud_div;
            end
        end else if (clk_cnt == 16'd0) begin
            shift     <= {1'b1, shift[9:1]};
            bits_left <= bits_left - 4'd1;
            clk_cnt   <= baud_div;
        end else begin
            clk_cnt <= clk_cnt - 16'd1;
        end
    end

endmodule

`default_nettype wire
