`default_nettype none
// Integer register file x0..x31: two combinational read ports, one write port.
// x0 reads as zero by the read muxes (the write port skips it as well), so the
// array itself needs no reset.  Read combinationally so that the execute
// cycle sees rs1/rs2 of the instruction register with no extra decode cycle.
module cpu_regfile (
    input  wire        clk,
    input  wire        we,
    input  wire [4:0]  waddr,
    input  wire [31:0] wdata,
    input  wire [4:0]  raddr1,
    output wire [31:0] rdata1,
    input  wire [4:0]  raddr2,
    output wire [31:0] rdata2
);
    reg [31:0] regs [0:31];

    // Defined start values make simulations reproducible; synthesis takes
    // them as the memory's power-up contents.
    integer i;
    initial begin
        for (i = 0; i < 32; i = i + 1)
            regs[i] = 32'd0;
    end

    always @(posedge clk) begin
        if (we && waddr != 5'd0)
            regs[waddr] <= wdata;
    end

    assign rdata1 = (raddr1 == 5'd0) ? 32'd0 : regs[raddr1];
    assign rdata2 = (raddr2 == 5'd0) ? 32'd0 : regs[raddr2];
endmodule
`default_nettype wire
