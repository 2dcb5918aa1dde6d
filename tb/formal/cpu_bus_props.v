// SPDX-License-Identifier: MIT
`default_nettype none
// Bus-contract properties of the CPU, proven by Yosys SAT (k-induction) for
// every input sequence: any wait states, any instruction words, acks and
// errors at any time (the environment is not constrained at all).
//   * a request not acknowledged in a cycle is still there in the next cycle
//     with the same address (and, on the data bus, the same we/be/wdata);
//   * retire never pulses in reset.
// PIPELINED selects the core: 0 tl_cpu, 1 tl_cpu_pipe (cpu_pipe_bus_props
// below is that instance, the top of the pipelined core's proof).
module cpu_bus_props #(
    parameter integer PIPELINED = 0
) (
    input wire        clk,
    input wire        rst,
    input wire        ibus_ack,
    input wire [31:0] ibus_rdata,
    input wire        ibus_err,
    input wire        dbus_ack,
    input wire [31:0] dbus_rdata,
    input wire        dbus_err,
    input wire        irq_timer,
    input wire        irq_external,
    input wire        irq_software,
    input wire [63:0] mtime
);
    wire        ibus_req, dbus_req, dbus_we, retire;
    wire [31:0] ibus_addr, dbus_addr, dbus_wdata;
    wire [3:0]  dbus_be;

    generate
        if (PIPELINED != 0) begin : g_pipe
            tl_cpu_pipe u_cpu (
                .clk(clk), .rst(rst),
                .ibus_req(ibus_req), .ibus_addr(ibus_addr), .ibus_ack(ibus_ack),
                .ibus_rdata(ibus_rdata), .ibus_err(ibus_err),
                .dbus_req(dbus_req), .dbus_addr(dbus_addr), .dbus_we(dbus_we), .dbus_be(dbus_be),
                .dbus_wdata(dbus_wdata), .dbus_ack(dbus_ack), .dbus_rdata(dbus_rdata), .dbus_err(dbus_err),
                .irq_timer(irq_timer), .irq_external(irq_external), .irq_software(irq_software),
                .mtime(mtime), .retire(retire)
            );
        end else begin : g_multi
            tl_cpu u_cpu (
                .clk(clk), .rst(rst),
                .ibus_req(ibus_req), .ibus_addr(ibus_addr), .ibus_ack(ibus_ack),
                .ibus_rdata(ibus_rdata), .ibus_err(ibus_err),
                .dbus_req(dbus_req), .dbus_addr(dbus_addr), .dbus_we(dbus_we), .dbus_be(dbus_be),
                .dbus_wdata(dbus_wdata), .dbus_ack(dbus_ack), .dbus_rdata(dbus_rdata), .dbus_err(dbus_err),
                .irq_timer(irq_timer), .irq_external(irq_external), .irq_software(irq_software),
                .mtime(mtime), .retire(retire)
            );
        end
    endgenerate

    reg        i_wait = 1'b0, d_wait = 1'b0;  // a request was left unanswered last cycle
    reg [31:0] i_addr_q, d_addr_q, d_wdata_q;
    reg        d_we_q;
    reg [3:0]  d_be_q;
    always @(posedge clk) begin
        i_wait    <= !rst && ibus_req && !ibus_ack;
        d_wait    <= !rst && dbus_req && !dbus_ack;
        i_addr_q  <= ibus_addr;
        d_addr_q  <= dbus_addr;
        d_we_q    <= dbus_we;
        d_be_q    <= dbus_be;
        d_wdata_q <= dbus_wdata;
    end

    always @(*) begin
        if (!rst && i_wait)
            assert(ibus_req && ibus_addr == i_addr_q);
        if (!rst && d_wait)
            assert(dbus_req && dbus_addr == d_addr_q && dbus_we == d_we_q &&
                   dbus_be == d_be_q && (!d_we_q || dbus_wdata == d_wdata_q));
        if (rst)
            assert(!retire && !ibus_req && !dbus_req);
    end
endmodule

// The pipelined core's proof: the same properties.
module cpu_pipe_bus_props (
    input wire        clk,
    input wire        rst,
    input wire        ibus_ack,
    input wire [31:0] ibus_rdata,
    input wire        ibus_err,
    input wire        dbus_ack,
    input wire [31:0] dbus_rdata,
    input wire        dbus_err,
    input wire        irq_timer,
    input wire        irq_external,
    input wire        irq_software,
    input wire [63:0] mtime
);
    cpu_bus_props #(.PIPELINED(1)) u_props (
        .clk(clk), .rst(rst), .ibus_ack(ibus_ack), .ibus_rdata(ibus_rdata), .ibus_err(ibus_err),
        .dbus_ack(dbus_ack), .dbus_rdata(dbus_rdata), .dbus_err(dbus_err),
        .irq_timer(irq_timer), .irq_external(irq_external), .irq_software(irq_software), .mtime(mtime)
    );
endmodule
`default_nettype wire
