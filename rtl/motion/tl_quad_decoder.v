// SPDX-License-Identifier: MIT
// tl_quad_decoder: 4x quadrature decoder for one optical encoder (A, B, index Z).
//
// The paper's decoder block (Sec. V.A, Fig. 8) counts encoder pulses into
// the position x that the controllers of eq. (20)-(22) close the loop on.
// This core adds what a real machine needs beyond that (as LinuxCNC's
// hostmot2 encoder does): a digital glitch filter, an illegal-transition
// counter, an index latch and count-edge timestamps for low-speed velocity.
//
// Pipeline, one clock domain:
//   enc_a/b/z --sync_2ff--> sync_abz --sample strobe + N-sample filter--> filt
//   filt vs prev --> +1 / -1 / illegal --> position, dir, timestamps
//
// Sampling: one sample every (sample_div + 1) clocks, f_s = CLK_HZ / (sample_div + 1).
// Filter:   a channel's filtered level changes only after the synchronised
//           input has differed from it on N = max(filter_len, 1) consecutive
//           samples; shorter pulses are ignored.  filter_len = 0 acts as 1.
// Maximum count rate (ideal 90 deg quadrature, every state equally long):
//           f_max = f_s * min(1, 2 / N) counts/s  (docs/quad_decoder.md has
//           the derivation and the table; derate for real encoder phase error).
// Counting: A leading B counts up.  A change of both A and B between two
//           samples is an illegal transition: position is held, the event is
//           counted (saturating) and illegal_flag is set until illegal_clear.
// Timestamps are in clock cycles (free-running `timestamp`); the position
// therefore changes by at most one per clock and per sample (proven by
// tb/formal/quad_decoder_props.v).
//
// Reset: the synchronisers are not reset, so that while rst is held (>= 3
// clocks) the filter and the previous-state register load the encoder's
// actual levels; leaving reset then produces no spurious count whatever
// position the shaft rests in.
`default_nettype none

module tl_quad_decoder #(
    parameter integer FILTER_BITS  = 4,   // width of filter_len: N up to 2^FILTER_BITS - 1 samples
    parameter integer DIV_BITS     = 16,  // width of sample_div (sample prescaler)
    parameter integer TS_BITS      = 32,  // timestamp width, clock cycles (32 bits = 85.9 s at 50 MHz)
    parameter integer ILLEGAL_BITS = 16   // illegal-transition counter width (saturates)
) (
    input  wire                    clk,
    input  wire                    rst,            // synchronous, active high; hold >= 3 clocks
    // encoder pins, asynchronous
    input  wire                    enc_a,
    input  wire                    enc_b,
    input  wire                    enc_z,          // tie low if the encoder has no index
    // run-time settings
    input  wire [DIV_BITS-1:0]     sample_div,     // sample every sample_div + 1 clocks
    input  wire [FILTER_BITS-1:0]  filter_len,     // N samples a level must persist (0 acts as 1)
    // commands (one-clock strobes)
    input  wire                    pos_load,       // position <= pos_load_val (wins over a count)
    input  wire [31:0]             pos_load_val,
    input  wire                    illegal_clear,  // clear illegal_count and illegal_flag
    input  wire                    index_arm,      // clear index_seen and latch at the next Z rise
    // state
    output reg  [31:0]             position,       // two's complement counts
    output reg                     dir,            // direction of the last count, 1 = up
    output reg  [ILLEGAL_BITS-1:0] illegal_count,
    output reg                     illegal_flag,
    output reg  [31:0]             index_pos,      // position just before the count of the Z rise
    output reg                     index_seen,
    output reg                     index_armed,
    output reg  [TS_BITS-1:0]      timestamp,      // free-running clock-cycle counter
    output reg  [TS_BITS-1:0]      last_edge_time, // timestamp of the last count
    output reg  [TS_BITS-1:0]      edge_interval,  // clocks between the last two counts (mod 2^TS_BITS)
    output wire [2:0]              enc_filtered    // filtered {z, b, a}, for diagnostics
);

    // --- synchronise (no reset: see header) -------------------------------------------
    wire [2:0] sync_abz;
    tl_sync_2ff #(.WIDTH(3), .RESET_VAL(0)) u_sync (
        .clk(clk), .rst(1'b0), .async_in({enc_z, enc_b, enc_a}), .sync_out(sync_abz)
    );

    // --- sample strobe --------------------------------------------------------------------
    reg  [DIV_BITS-1:0] div_cnt;
    wire                sample = (div_cnt == {DIV_BITS{1'b0}});

    always @(posedge clk) begin
        if (rst || sample)
            div_cnt <= rst ? {DIV_BITS{1'b0}} : sample_div;
        else
            div_cnt <= div_cnt - 1'b1;
    end

    // --- glitch filter, one counter per channel ----------------------------------------------
    // filt_cnt holds, per channel, how many consecutive samples so far have
    // disagreed with the filtered level.
    reg [2:0]               filt;
    reg [3*FILTER_BITS-1:0] filt_cnt;
    wire [FILTER_BITS:0]    n_eff = (filter_len == {FILTER_BITS{1'b0}})
                                    ? {{FILTER_BITS{1'b0}}, 1'b1} : {1'b0, filter_len};
    integer i;

    always @(posedge clk) begin
        if (rst) begin
            filt     <= sync_abz;
            filt_cnt <= {3*FILTER_BITS{1'b0}};
        end else if (sample) begin
            for (i = 0; i < 3; i = i + 1) begin
                if (sync_abz[i] == filt[i])
                    filt_cnt[i*FILTER_BITS +: FILTER_BITS] <= {FILTER_BITS{1'b0}};
                else if ({1'b0, filt_cnt[i*FILTER_BITS +: FILTER_BITS]} + 1'b1 >= n_eff) begin
                    filt[i] <= sync_abz[i];
                    filt_cnt[i*FILTER_BITS +: FILTER_BITS] <= {FILTER_BITS{1'b0}};
                end else
                    filt_cnt[i*FILTER_BITS +: FILTER_BITS] <= filt_cnt[i*FILTER_BITS +: FILTER_BITS] + 1'b1;
            end
        end
    end

    assign enc_filtered = filt;

    // --- 4x decode -----------------------------------------------------------------------------
    // filt changes only on sample clocks, so comparing it with its value one
    // clock earlier sees each sample's change exactly once.
    reg  [2:0] prev;
    wire       step    = (filt[0] ^ prev[0]) ^ (filt[1] ^ prev[1]);   // exactly one channel changed
    wire       illegal = (filt[0] ^ prev[0]) & (filt[1] ^ prev[1]);   // both changed
    wire       up      = prev[1] ^ filt[0];                           // A leads B: old B xor new A
    wire       z_rise  = filt[2] & ~prev[2];

    always @(posedge clk) begin
        if (rst) begin
            prev           <= sync_abz;
            position       <= 32'd0;
            dir            <= 1'b0;
            timestamp      <= {TS_BITS{1'b0}};
            last_edge_time <= {TS_BITS{1'b0}};
            edge_interval  <= {TS_BITS{1'b0}};
        end else begin
            prev      <= filt;
            timestamp <= timestamp + 1'b1;
            if (step) begin
                dir            <= up;
                last_edge_time <= timestamp;
                edge_interval  <= timestamp - last_edge_time;
            end
            if (pos_load)
                position <= pos_load_val;
            else if (step)
                position <= up ? position + 32'd1 : position - 32'd1;
        end
    end

    // --- illegal transitions: a count would be a guess, so none is made -----------------------------
    always @(posedge clk) begin
        if (rst) begin
            illegal_count <= {ILLEGAL_BITS{1'b0}};
            illegal_flag  <= 1'b0;
        end else if (illegal) begin
            // an event in the clearing clock is kept: it happened after the read
            illegal_flag <= 1'b1;
            if (illegal_clear)
                illegal_count <= {{ILLEGAL_BITS-1{1'b0}}, 1'b1};
            else if (illegal_count != {ILLEGAL_BITS{1'b1}})
                illegal_count <= illegal_count + 1'b1;
        end else if (illegal_clear) begin
            illegal_count <= {ILLEGAL_BITS{1'b0}};
            illegal_flag  <= 1'b0;
        end
    end

    // --- index latch ----------------------------------------------------------------------------------
    always @(posedge clk) begin
        if (rst) begin
            index_pos   <= 32'd0;
            index_seen  <= 1'b0;
            index_armed <= 1'b0;
        end else if (index_arm) begin
            index_seen  <= 1'b0;
            index_armed <= 1'b1;
        end else if (index_armed && z_rise) begin
            index_pos   <= position;
            index_seen  <= 1'b1;
            index_armed <= 1'b0;
        end
    end

endmodule

`default_nettype wire
