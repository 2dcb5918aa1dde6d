// SPDX-License-Identifier: MIT
`default_nettype none
// Instruction fetch: the instruction bus master, the instruction register
// and a one-word prefetch buffer.
//
// At most one request is outstanding.  A request starts with `start`
// (address `start_addr`, driven combinationally in that cycle so the bus
// latency overlaps it) and is then held, address registered, until
// ibus_ack.  The core only raises `start` when no request is outstanding or
// in the ack cycle of the outstanding one, so ibus_req/ibus_addr never
// change under a pending request and no fetch is ever cancelled: a slave
// may take any number of wait states.
//
// Two kinds of fetch:
//   * in FETCH (`waiting`): the word goes straight into the instruction
//     register (`fetched`), or raises `fault` on ibus_err;
//   * while a load/store or multiply/divide is in flight (`prefetching`):
//     the core prefetched pc+4; the word waits in the prefetch buffer (or
//     is taken from the bus in its ack cycle) until the core moves it into
//     the instruction register with `take_prefetch`.
module tl_cpu_fetch (
    input  wire        clk,
    input  wire        rst,
    input  wire        start,
    input  wire [31:0] start_addr,
    input  wire        waiting,
    input  wire        prefetching,
    input  wire        take_prefetch,
    output wire        ibus_req,
    output wire [31:0] ibus_addr,
    input  wire        ibus_ack,
    input  wire [31:0] ibus_rdata,
    input  wire        ibus_err,
    output wire        pending,       // a request is outstanding
    output reg  [31:0] insn,
    output wire [31:0] insn_next,     // the word insn loads at this edge (valid with insn_load)
    output wire        insn_load,     // insn loads a new word at this edge ...
    output wire [4:0]  next_rs1,      // ... whose register numbers these are
    output wire [4:0]  next_rs2,
    output wire        fetched,       // FETCH: ack without error, insn valid next cycle
    output wire        fault,         // FETCH: ack with error
    output wire        pf_done,       // prefetch answered (now or before)
    output wire        pf_bad         // ... with a bus error
);
    reg        pend;
    reg [31:0] addr_q;
    reg [31:0] pf_insn;
    reg        pf_err;

    assign pending   = pend;
    assign ibus_req  = !rst && (pend || start);  // quiet in reset, whatever pend powered up as
    assign ibus_addr = pend ? addr_q : start_addr;
    assign fetched   = waiting && pend && ibus_ack && !ibus_err;
    assign fault     = waiting && pend && ibus_ack && ibus_err;
    assign pf_done   = !pend || ibus_ack;
    assign pf_bad    = pend ? ibus_err : pf_err;
    wire [31:0] pf_word = pend ? ibus_rdata : pf_insn;
    assign insn_load = fetched || take_prefetch;
    assign insn_next = fetched ? ibus_rdata : pf_word;
    assign next_rs1  = insn_next[19:15];
    assign next_rs2  = insn_next[24:20];

    always @(posedge clk) begin
        if (rst) begin
            pend <= 1'b0;
        end else if (start) begin
            pend   <= 1'b1;
            addr_q <= start_addr;
        end else if (ibus_ack) begin
            pend <= 1'b0;
        end
    end

    always @(posedge clk) begin
        if (prefetching && pend && ibus_ack) begin
            pf_insn <= ibus_rdata;
            pf_err  <= ibus_err;
        end
        if (insn_load)
            insn <= insn_next;
    end
endmodule
`default_nettype wire
