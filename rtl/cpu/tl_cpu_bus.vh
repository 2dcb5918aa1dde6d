// SPDX-License-Identifier: MIT
// The CPU's bus and interrupt signals, written once for every module that
// has them as ports or wires: the two cores (tl_cpu, tl_cpu_pipe), the SoC
// fabric that answers them, the SoC and the test harnesses that wire a core
// (tb/cpu/cpu_sim_top.v, tb/formal/cpu_bus_props.v).  The handshake is the
// one tl_cpu.v describes.  Macros, not module items: a port list cannot come
// from a localparam.  The names have no TL_ prefix because they are not
// register-map names (regmap.vh).
`ifndef TL_CPU_BUS_VH
`define TL_CPU_BUS_VH

// Instruction and data bus ports: M is the direction of what the master
// drives (request, address, write fields), S of what the slave answers
// (ack, read data, error) - (output, input) in a core, (input, output) in
// the fabric.
`define CPU_BUS_PORTS(M, S) \
    M wire        ibus_req, \
    M wire [31:0] ibus_addr, \
    S wire        ibus_ack, \
    S wire [31:0] ibus_rdata, \
    S wire        ibus_err, \
    M wire        dbus_req, \
    M wire [31:0] dbus_addr, \
    M wire        dbus_we, \
    M wire [3:0]  dbus_be, \
    M wire [31:0] dbus_wdata, \
    S wire        dbus_ack, \
    S wire [31:0] dbus_rdata, \
    S wire        dbus_err

// The interrupt levels and the machine timer: inputs of a core, outputs of
// the fabric (D is their direction).
`define CPU_IRQ_PORTS(D) \
    D wire        irq_timer, \
    D wire        irq_external, \
    D wire        irq_software, \
    D wire [63:0] mtime

// The master's side of the buses as wires (a module that instantiates a core
// and drives its inputs from registers declares those itself).
`define CPU_BUS_MASTER_WIRES \
    wire        ibus_req, dbus_req, dbus_we; \
    wire [31:0] ibus_addr, dbus_addr, dbus_wdata; \
    wire [3:0]  dbus_be;

// Both sides of the buses, the interrupt levels and the timer as wires.
`define CPU_BUS_WIRES \
    `CPU_BUS_MASTER_WIRES \
    wire        ibus_ack, ibus_err, dbus_ack, dbus_err; \
    wire [31:0] ibus_rdata, dbus_rdata; \
    wire [63:0] mtime; \
    wire        irq_timer, irq_software, irq_external;

// Named connections of the bus ports and of the interrupt ports to the
// signals of the same names.
`define CPU_BUS_CONNECT \
    .ibus_req(ibus_req), .ibus_addr(ibus_addr), .ibus_ack(ibus_ack), \
    .ibus_rdata(ibus_rdata), .ibus_err(ibus_err), \
    .dbus_req(dbus_req), .dbus_addr(dbus_addr), .dbus_we(dbus_we), .dbus_be(dbus_be), \
    .dbus_wdata(dbus_wdata), .dbus_ack(dbus_ack), .dbus_rdata(dbus_rdata), .dbus_err(dbus_err)
`define CPU_IRQ_CONNECT \
    .irq_timer(irq_timer), .irq_external(irq_external), .irq_software(irq_software), .mtime(mtime)

// The whole interface of a core, shared by tl_cpu and tl_cpu_pipe: its
// parameters (RESET_PC: the first fetch address; HART_ID: mhartid), its
// ports (clk, synchronous active-high rst, the buses, the interrupts, and
// retire: one pulse per retired instruction) and their named connection.
`define CPU_CORE_PARAMS \
    parameter [31:0] RESET_PC = 32'h0000_0000, \
    parameter [31:0] HART_ID  = 32'd0
`define CPU_CORE_PORTS \
    input  wire        clk, \
    input  wire        rst, \
    `CPU_BUS_PORTS(output, input), \
    `CPU_IRQ_PORTS(input), \
    output wire        retire
`define CPU_CORE_CONNECT \
    .clk(clk), .rst(rst), `CPU_BUS_CONNECT, `CPU_IRQ_CONNECT, .retire(retire)

`endif
