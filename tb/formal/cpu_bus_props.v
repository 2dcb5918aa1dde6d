// SPDX-License-Identifier: MIT
`default_nettype none
// Bus-contract properties of the CPU, proven by Yosys SAT (k-induction) for
// every input sequence: any wait states, any instruction words, acks and
// errors at any time (the environment is not constrained at all).
//   * a request not acknowledged in a cycle is still there in the next cycle
//     with the same address (and, on the data bus, the same we/be/wdata):
//     tl_cpu holds it through its ack cycle too (HOLD_THROUGH_ACK = 1:
//     unacknowledged in cycle t -> unchanged in t+1, the ack cycle);
//     tl_cpu_pipe holds it until the ack and may show its next request in
//     the ack cycle (HOLD_THROUGH_ACK = 0: requested in t and no ack in t+1
//     -> unchanged in t+1);
//   * retire never pulses in reset.
// cpu_bus_contract holds the properties; cpu_bus_props proves them for
// tl_cpu, cpu_pipe_bus_props for tl_cpu_pipe.
module cpu_bus_contract #(
    parameter integer HOLD_THROUGH_ACK = 1
) (
    input wire        clk,
    input wire        rst,
    input wire        ibus_req,
    input wire [31:0] ibus_addr,
    input wire        ibus_ack,
    input wire        dbus_req,
    input wire [31:0] dbus_addr,
    input wire        dbus_we,
    input wire [3:0]  dbus_be,
    input wire [31:0] dbus_wdata,
    input wire        dbus_ack,
    input wire        retire
);
    localparam HOLD = HOLD_THROUGH_ACK != 0;
    reg        i_wait = 1'b0, d_wait = 1'b0;  // a request was there last cycle (and unanswered, if HOLD)
    reg [31:0] i_addr_q, d_addr_q, d_wdata_q;
    reg        d_we_q;
    reg [3:0]  d_be_q;
    always @(posedge clk) begin
        i_wait    <= !rst && ibus_req && (!HOLD || !ibus_ack);
        d_wait    <= !rst && dbus_req && (!HOLD || !dbus_ack);
        i_addr_q  <= ibus_addr;
        d_addr_q  <= dbus_addr;
        d_we_q    <= dbus_we;
        d_be_q    <= dbus_be;
        d_wdata_q <= dbus_wdata;
    end

    always @(*) begin
        if (!rst && i_wait && (HOLD || !ibus_ack))
            assert(ibus_req && ibus_addr == i_addr_q);
        if (!rst && d_wait && (HOLD || !dbus_ack))
            assert(dbus_req && dbus_addr == d_addr_q && dbus_we == d_we_q &&
                   dbus_be == d_be_q && (!d_we_q || dbus_wdata == d_wdata_q));
        if (rst)
            assert(!retire && !ibus_req && !dbus_req);
    end
endmodule

module cpu_bus_props #(
    parameter integer HOLD_THROUGH_ACK = 1
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

    tl_cpu u_cpu (
        .clk(clk), .rst(rst),
        .ibus_req(ibus_req), .ibus_addr(ibus_addr), .ibus_ack(ibus_ack),
        .ibus_rdata(ibus_rdata), .ibus_err(ibus_err),
        .dbus_req(dbus_req), .dbus_addr(dbus_addr), .dbus_we(dbus_we), .dbus_be(dbus_be),
        .dbus_wdata(dbus_wdata), .dbus_ack(dbus_ack), .dbus_rdata(dbus_rdata), .dbus_err(dbus_err),
        .irq_timer(irq_timer), .irq_external(irq_external), .irq_software(irq_software),
        .mtime(mtime), .retire(retire)
    );
    cpu_bus_contract #(.HOLD_THROUGH_ACK(HOLD_THROUGH_ACK)) u_contract (
        .clk(clk), .rst(rst), .ibus_req(ibus_req), .ibus_addr(ibus_addr), .ibus_ack(ibus_ack),
        .dbus_req(dbus_req), .dbus_addr(dbus_addr), .dbus_we(dbus_we), .dbus_be(dbus_be),
        .dbus_wdata(dbus_wdata), .dbus_ack(dbus_ack), .retire(retire)
    );
endmodule

module cpu_pipe_bus_props #(
    parameter integer HOLD_THROUGH_ACK = 0
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

    tl_cpu_pipe u_cpu (
        .clk(clk), .rst(rst),
        .ibus_req(ibus_req), .ibus_addr(ibus_addr), .ibus_ack(ibus_ack),
        .ibus_rdata(ibus_rdata), .ibus_err(ibus_err),
        .dbus_req(dbus_req), .dbus_addr(dbus_addr), .dbus_we(dbus_we), .dbus_be(dbus_be),
        .dbus_wdata(dbus_wdata), .dbus_ack(dbus_ack), .dbus_rdata(dbus_rdata), .dbus_err(dbus_err),
        .irq_timer(irq_timer), .irq_external(irq_external), .irq_software(irq_software),
        .mtime(mtime), .retire(retire)
    );
    cpu_bus_contract #(.HOLD_THROUGH_ACK(HOLD_THROUGH_ACK)) u_contract (
        .clk(clk), .rst(rst), .ibus_req(ibus_req), .ibus_addr(ibus_addr), .ibus_ack(ibus_ack),
        .dbus_req(dbus_req), .dbus_addr(dbus_addr), .dbus_we(dbus_we), .dbus_be(dbus_be),
        .dbus_wdata(dbus_wdata), .dbus_ack(dbus_ack), .retire(retire)
    );
endmodule
`default_nettype wire
