// SPDX-License-Identifier: MIT
// tl_sync_2ff: WIDTH independent two-flop synchronisers for asynchronous inputs.
//
// Every board input (encoder channels, UART RX, keys, switches, bridge fault
// comparators) enters the clock domain through one of these.  The bits are
// synchronised independently, so a multi-bit bus must not be passed through
// it (use a handshake or Gray code for that).  RESET_VAL is the value the
// flops take in reset, chosen per use as the input's idle level (1 for
// UART RX, 0 for an encoder channel), so that releasing reset produces no
// false edge downstream.
//
// Latency: a change on async_in is visible on sync_out after 2 to 3 clock
// edges (2 plus the fraction of a cycle before the first capturing edge).
`default_nettype none

module tl_sync_2ff #(
    parameter integer WIDTH     = 1,
    parameter integer RESET_VAL = 0   // replicated into every bit
) (
    input  wire             clk,
    input  wire             rst,      // synchronous, active high
    input  wire [WIDTH-1:0] async_in,
    output wire [WIDTH-1:0] sync_out
);

    localparam [WIDTH-1:0] RST_VEC = {WIDTH{RESET_VAL[0]}};

    // Quartus recognises the pair as a synchroniser chain by this attribute
    // and keeps the two flops adjacent for maximum metastability settling time.
    (* altera_attribute = "-name SYNCHRONIZER_IDENTIFICATION FORCED_IF_ASYNCHRONOUS" *)
    reg [WIDTH-1:0] meta;
    (* altera_attribute = "-name SYNCHRONIZER_IDENTIFICATION FORCED_IF_ASYNCHRONOUS" *)
    reg [WIDTH-1:0] stable;

    always @(posedge clk) begin
        if (rst) begin
            meta   <= RST_VEC;
            stable <= RST_VEC;
        end else begin
            meta   <= async_in;
            stable <= meta;
        end
    end

    assign sync_out = stable;

endmodule

`default_nettype wire
