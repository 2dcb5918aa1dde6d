// SPDX-License-Identifier: MIT
// tl_uart_rx: 8N1 receiver with a run-time bit period, three-sample majority
// vote, framing-error and break detection.
//
// rxd is asynchronous (the RN-XV's TX pin) and enters through sync_2ff with
// RESET_VAL = 1, the idle level, so reset never looks like a start bit.
//
// Timing, with L = baud_div + 1 clocks per bit (L >= 16):
//  - every decision reads rx, which shows the line as it was two clocks
//    earlier (synchroniser); the counter is set to 1 when the start edge is
//    first seen, which makes counter value v read the line between v and
//    v + 1 clocks after the start edge (the synchroniser's delay cancels);
//  - each bit is sampled at L/2 - L/16, L/2 and L/2 + L/16 clocks into the bit
//    (the middle three points of 16x oversampling, at clock resolution) and
//    decided by majority, so one disturbed sample does not flip a bit;
//  - a start bit that votes high is a glitch: back to idle;
//  - the frame is decided at the third sample of the stop bit, leaving
//    half a bit for the next start edge (tolerates the sender being up to
//    ~4 % fast or slow);
//  - stop bit low: frame_error; if all data bits were low too, the line is
//    held low (a break): break_detect as well.  Either way the receiver then
//    waits for the line to go high before it looks for a start bit, so a
//    long break gives one event, not a stream of zero bytes.
// m_valid, frame_error and break_detect are one-clock pulses; there is no
// ready (a UART cannot be stalled): the FIFO in uart.v counts what it drops.
`default_nettype none

module tl_uart_rx (
    input  wire        clk,
    input  wire        rst,          // synchronous, active high
    input  wire [15:0] baud_div,     // clocks per bit - 1, >= 15
    input  wire        rxd,          // asynchronous, idle high
    output wire [7:0]  m_data,       // valid with m_valid
    output reg         m_valid,
    output reg         frame_error,
    output reg         break_detect
);

    localparam [1:0] IDLE = 2'd0, RUN = 2'd1, WAIT_HIGH = 2'd2;
    localparam [16:0] START_CNT = 17'd1;   // see the header: cancels the synchroniser delay

    wire rx;
    tl_sync_2ff #(.WIDTH(1), .RESET_VAL(1)) u_sync (
        .clk(clk), .rst(rst), .async_in(rxd), .sync_out(rx)
    );

    reg [1:0]  state;
    reg [15:0] clk_cnt;     // clocks into the current bit
    reg [3:0]  bit_idx;     // 0 start, 1-8 data, 9 stop
    reg [1:0]  votes;       // first two samples of the current bit
    reg [7:0]  data_sr;

    /* verilator lint_off UNUSEDSIGNAL */  // bit 0: only L/2 and L/16 are used
    wire [16:0] bit_len = {1'b0, baud_div} + 17'd1;
    /* verilator lint_on UNUSEDSIGNAL */
    wire [16:0] mid     = {1'b0, bit_len[16:1]};
    wire [16:0] sixth   = {4'd0, bit_len[16:4]};   // a sixteenth of a bit
    wire [16:0] cnt     = {1'b0, clk_cnt};
    wire        bit_val = (votes[0] & votes[1]) | (votes[0] & rx) | (votes[1] & rx);

    assign m_data = data_sr;

    always @(posedge clk) begin
        m_valid      <= 1'b0;
        frame_error  <= 1'b0;
        break_detect <= 1'b0;
        if (rst) begin
            state   <= IDLE;
            clk_cnt <= 16'd0;
            bit_idx <= 4'd0;
            votes   <= 2'b11;
            data_sr <= 8'd0;
        end else begin
            case (state)
                IDLE:
                    if (!rx) begin
                        state   <= RUN;
                        clk_cnt <= START_CNT[15:0];
                        bit_idx <= 4'd0;
                    end
                RUN: begin
                    if (clk_cnt == baud_div)
                        clk_cnt <= 16'd0;
                    else
                        clk_cnt <= clk_cnt + 16'd1;
                    if (clk_cnt == baud_div)
                        bit_idx <= bit_idx + 4'd1;

                    if (cnt == mid - sixth)
                        votes[0] <= rx;
                    if (cnt == mid)
                        votes[1] <= rx;
                    if (cnt == mid + sixth) begin
                        if (bit_idx == 4'd0) begin
                            if (bit_val)
                                state <= IDLE;          // glitch, not a start bit
                        end else if (bit_idx != 4'd9) begin
                            data_sr <= {bit_val, data_sr[7:1]};
                        end else if (bit_val) begin
                            m_valid <= 1'b1;
                            state   <= IDLE;
                        end else begin
                            frame_error  <= 1'b1;
                            break_detect <= (data_sr == 8'd0);
                            state        <= WAIT_HIGH;
                        end
                    end
                end
                default:  // WAIT_HIGH
                    if (rx)
                        state <= IDLE;
            endcase
        end
    end

endmodule

`default_nettype wire
