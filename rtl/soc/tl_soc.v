// SPDX-License-Identifier: MIT
// tl_soc: the torqueloop system on chip - the RV32IM CPU (rtl/cpu) on the
// fabric of rtl/soc/tl_soc_fabric.v (interconnect, boot ROM, RAM, machine
// timer, interrupt controller, GPIO, UART, two motor axes, safety latch).
//
// This is the paper's "own FPGA-based programmable microprocessor"
// (sections I, V.A) with its frequency, PWM and decoder blocks as
// memory-mapped peripherals: firmware (C, compiled to the hex images named
// by ROM_INIT / RAM_INIT) runs the P/PD/PID laws of eq. (20)-(22) and writes
// the PWM command of eq. (1).  The memory and register map is
// torqueloop/spec/regmap.toml; docs/soc.md describes the blocks.
//
// The board top (rtl/board/de0_cv_top.v) supplies clk and a synchronous
// reset (reset_sync) and wires the pins; every asynchronous input is
// synchronised inside the fabric.
// the register map's TL_* names (generated; the include guard makes a second include empty)
`include "regmap.vh"
`default_nettype none

module tl_soc #(
    parameter integer RAM_BYTES        = `TL_RAM_SIZE,
    parameter         RAM_INIT         = "",
    parameter         ROM_INIT         = "",
    parameter [31:0]  BUILD_ID         = 32'd0,
    parameter integer CLK_HZ           = `TL_CLK_HZ,
    parameter [31:0]  HART_ID          = 32'd0,
    parameter integer LIMIT_DEBOUNCE_CLKS = 50_000,  // limit switch debounce, 1 ms
    // the CPU: 0 tl_cpu (multi-cycle), 1 tl_cpu_pipe (pipelined, on a fabric
    // that takes a request every cycle); docs/cpu.md
    parameter integer CPU_PIPELINED    = 0
) (
    input  wire        clk,
    input  wire        rst,            // synchronous, active high
    output wire [9:0]  ledr,
    input  wire [9:0]  sw,
    input  wire [3:0]  key_n,
    output wire [6:0]  hex0_n,
    output wire [6:0]  hex1_n,
    output wire [6:0]  hex2_n,
    output wire [6:0]  hex3_n,
    output wire [6:0]  hex4_n,
    output wire [6:0]  hex5_n,
    output wire [1:0]  rpwm,
    output wire [1:0]  lpwm,
    output wire [1:0]  r_en,
    output wire [1:0]  l_en,
    output wire [1:0]  pwm,
    output wire [1:0]  dir,
    input  wire [1:0]  bridge_fault,
    input  wire [1:0]  enc_a,
    input  wire [1:0]  enc_b,
    input  wire [1:0]  enc_z,
    input  wire        uart_rx,
    output wire        uart_tx,
    input  wire        uart_cts_n,
    output wire        uart_rts_n,
    input  wire        estop,
    input  wire [1:0]  lim_neg,        // limit switches, asynchronous, 1 = open (tripped), per axis
    input  wire [1:0]  lim_pos,
    output wire        wdog_alive      // hardware watchdog armed and not expired (to the drive interlock)
);

    wire        ibus_req, ibus_ack, ibus_err;
    wire [31:0] ibus_addr, ibus_rdata;
    wire        dbus_req, dbus_we, dbus_ack, dbus_err;
    wire [3:0]  dbus_be;
    wire [31:0] dbus_addr, dbus_wdata, dbus_rdata;
    wire [63:0] mtime;
    wire        irq_timer, irq_software, irq_external;
    /* verilator lint_off UNUSEDSIGNAL */
    wire        retire;   // instruction-retired pulse: for test benches (instruction counts)
    /* verilator lint_on UNUSEDSIGNAL */

    generate
        if (CPU_PIPELINED != 0) begin : g_pipe
            tl_cpu_pipe #(.RESET_PC(`TL_BOOT_ROM_BASE), .HART_ID(HART_ID)) u_cpu (
                .clk(clk), .rst(rst),
                .ibus_req(ibus_req), .ibus_addr(ibus_addr), .ibus_ack(ibus_ack),
                .ibus_rdata(ibus_rdata), .ibus_err(ibus_err),
                .dbus_req(dbus_req), .dbus_addr(dbus_addr), .dbus_we(dbus_we), .dbus_be(dbus_be),
                .dbus_wdata(dbus_wdata), .dbus_ack(dbus_ack), .dbus_rdata(dbus_rdata), .dbus_err(dbus_err),
                .irq_timer(irq_timer), .irq_external(irq_external), .irq_software(irq_software),
                .mtime(mtime), .retire(retire)
            );
        end else begin : g_multi
            tl_cpu #(.RESET_PC(`TL_BOOT_ROM_BASE), .HART_ID(HART_ID)) u_cpu (
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

    tl_soc_fabric #(
        .RAM_BYTES(RAM_BYTES), .RAM_INIT(RAM_INIT), .ROM_INIT(ROM_INIT), .BUILD_ID(BUILD_ID),
        .CLK_HZ(CLK_HZ), .LIMIT_DEBOUNCE_CLKS(LIMIT_DEBOUNCE_CLKS), .PIPELINED(CPU_PIPELINED)
    ) u_fabric (
        .clk(clk), .rst(rst),
        .ibus_req(ibus_req), .ibus_addr(ibus_addr), .ibus_ack(ibus_ack),
        .ibus_rdata(ibus_rdata), .ibus_err(ibus_err),
        .dbus_req(dbus_req), .dbus_addr(dbus_addr), .dbus_we(dbus_we), .dbus_be(dbus_be),
        .dbus_wdata(dbus_wdata), .dbus_ack(dbus_ack), .dbus_rdata(dbus_rdata), .dbus_err(dbus_err),
        .mtime(mtime), .irq_timer(irq_timer), .irq_software(irq_software), .irq_external(irq_external),
        .ledr(ledr), .sw(sw), .key_n(key_n),
        .hex0_n(hex0_n), .hex1_n(hex1_n), .hex2_n(hex2_n), .hex3_n(hex3_n), .hex4_n(hex4_n), .hex5_n(hex5_n),
        .rpwm(rpwm), .lpwm(lpwm), .r_en(r_en), .l_en(l_en), .pwm(pwm), .dir(dir),
        .bridge_fault(bridge_fault), .enc_a(enc_a), .enc_b(enc_b), .enc_z(enc_z),
        .uart_rx(uart_rx), .uart_tx(uart_tx), .uart_cts_n(uart_cts_n), .uart_rts_n(uart_rts_n),
        .estop(estop), .lim_neg(lim_neg), .lim_pos(lim_pos), .wdog_alive(wdog_alive)
    );

endmodule

`default_nettype wire
