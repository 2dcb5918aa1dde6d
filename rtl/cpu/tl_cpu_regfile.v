// SPDX-License-Identifier: MIT
`default_nettype none
// Integer register file x0..x31 in block RAM: one write port, two read
// ports with registered (synchronous) reads, as Cyclone V M10K/MLAB blocks
// provide them.  Each read port has its own copy of the 32 words, since a
// simple-dual-port block RAM has one read port.
// Intel template: "Single-Clock Synchronous RAM with Old Data
// Read-During-Write Behavior" (Quartus Prime Recommended HDL Coding
// Styles), simple dual port, one per copy, with a read enable (`re`) on the
// registered read.
//
// The core reads in the cycle its instruction register loads (`re`, with
// the register numbers of the incoming instruction word); rdata holds
// until the next `re`, so rs1/rs2 stay valid through multi-cycle
// instructions.  A write in the same cycle as the read of the same
// register is forwarded (the block RAM would return the old word), and x0
// reads as zero whatever the RAM holds.
module tl_cpu_regfile (
    input  wire        clk,
    input  wire        we,
    input  wire [4:0]  waddr,
    input  wire [31:0] wdata,
    input  wire        re,
    input  wire [4:0]  raddr1,
    input  wire [4:0]  raddr2,
    output wire [31:0] rdata1,
    output wire [31:0] rdata2,
    // the banks' registered words alone (no x0, no write forwarding), for a
    // core that makes those choices itself (tl_cpu_pipe)
    output wire [31:0] word1,
    output wire [31:0] word2
);
`ifdef FORMAL
    // Yosys sat cannot take memory cells: the proofs see plain registers.
    (* mem2reg *) reg [31:0] bank1 [0:31];
    (* mem2reg *) reg [31:0] bank2 [0:31];
`else
    reg [31:0] bank1 [0:31];
    reg [31:0] bank2 [0:31];
`endif
    reg [31:0] q1, q2, fwd;
    reg        use_fwd1, use_fwd2, zero1, zero2;

`ifndef SYNTHESIS
    // Defined start values make simulations reproducible.  Left out of
    // synthesis: Yosys 0.23 will not map an initialised memory to M10K, and
    // software must not rely on register values at reset anyway.
    integer i;
    initial begin
        for (i = 0; i < 32; i = i + 1) begin
            bank1[i] = 32'd0;
            bank2[i] = 32'd0;
        end
    end
`endif

    always @(posedge clk) begin
        if (we) begin
            bank1[waddr] <= wdata;
            bank2[waddr] <= wdata;
        end
        if (re) begin
            q1 <= bank1[raddr1];
            q2 <= bank2[raddr2];
        end
    end

    always @(posedge clk) begin
        if (re) begin
            fwd      <= wdata;
            use_fwd1 <= we && waddr == raddr1;
            use_fwd2 <= we && waddr == raddr2;
            zero1    <= raddr1 == 5'd0;
            zero2    <= raddr2 == 5'd0;
        end
    end

    assign rdata1 = zero1 ? 32'd0 : (use_fwd1 ? fwd : q1);
    assign rdata2 = zero2 ? 32'd0 : (use_fwd2 ? fwd : q2);
    assign word1  = q1;
    assign word2  = q2;
endmodule
`default_nettype wire
