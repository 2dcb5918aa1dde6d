// SPDX-License-Identifier: MIT
`default_nettype none
`include "tl_cpu_bus.vh"
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
// tl_cpu, cpu_pipe_bus_props for tl_cpu_pipe (both through cpu_bus_check).
module cpu_bus_contract #(
    parameter integer HOLD_THROUGH_ACK = 1
) (
    input wire        clk,
    input wire        rst,
    /* the answers (rdata, err) are not part of the contract */
    `CPU_BUS_PORTS(input, input),
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

// The core under the contract; a top below picks which.  PIPELINED has no
// default core: Yosys elaborates every module of the file with its
// defaults, and each manifest core holds only its own CPU.
module cpu_bus_check #(
    parameter integer PIPELINED = -1     // 0: tl_cpu, 1: tl_cpu_pipe
) (`CPU_CORE_PORTS);
    generate
        if (PIPELINED == 1) begin : g_pipe
            tl_cpu_pipe u_cpu (`CPU_CORE_CONNECT);
        end else if (PIPELINED == 0) begin : g_multi
            tl_cpu u_cpu (`CPU_CORE_CONNECT);
        end
    endgenerate
    cpu_bus_contract #(.HOLD_THROUGH_ACK(PIPELINED == 0)) u_contract (
        .clk(clk), .rst(rst), `CPU_BUS_CONNECT, .retire(retire)
    );
endmodule

// The tops (rtl/manifest.toml): the core's ports are theirs, the slave side
// and the interrupts free inputs.
module cpu_bus_props (`CPU_CORE_PORTS);
    cpu_bus_check #(.PIPELINED(0)) u_check (`CPU_CORE_CONNECT);
endmodule

module cpu_pipe_bus_props (`CPU_CORE_PORTS);
    cpu_bus_check #(.PIPELINED(1)) u_check (`CPU_CORE_CONNECT);
endmodule
`default_nettype wire
