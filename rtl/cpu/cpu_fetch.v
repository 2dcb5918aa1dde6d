`default_nettype none
// Instruction fetch: drives the instruction bus and holds the fetched word.
//
// A fetch is requested in two ways, both holding ibus_req and ibus_addr
// stable until ibus_ack:
//   * `launch` in the cycle an instruction completes: the request goes out at
//     once with the next pc, so the bus latency overlaps that cycle;
//   * `waiting`: the core's FETCH state, holding the request (addr = pc) until ack.
// There is never more than one request outstanding, so no fetch is ever
// cancelled and a slave may take any number of wait states.
module cpu_fetch (
    input  wire        clk,
    input  wire        launch,
    input  wire [31:0] next_pc,
    input  wire        waiting,
    input  wire [31:0] pc,
    output wire        ibus_req,
    output wire [31:0] ibus_addr,
    input  wire        ibus_ack,
    input  wire [31:0] ibus_rdata,
    input  wire        ibus_err,
    output reg  [31:0] insn,
    output wire        fetched,    // ack without error: insn valid from the next cycle
    output wire        fault       // ack with error: instruction access fault
);
    assign ibus_req  = launch || waiting;
    assign ibus_addr = launch ? next_pc : pc;
    assign fetched   = waiting && ibus_ack && !ibus_err;
    assign fault     = waiting && ibus_ack && ibus_err;

    always @(posedge clk) begin
        if (fetched)
            insn <= ibus_rdata;
    end
endmodule
`default_nettype wire
