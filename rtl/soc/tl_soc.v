// SPDX-License-Identifier: MIT
// tl_soc: the torqueloop system on chip - the RV32IM CPU (rtl/cpu) on the
// fabric of rtl/soc/tl_soc_fabric.v (interconnect, boot ROM, RAM, machine
// timer, interrupt controller, GPIO, UART, two motor axes, safety latch,
// the configuration flash's serial port).
//
// This is the paper's "own FPGA-based programmable microprocessor"
// (sections I, V.A) with its frequency, PWM and decoder blocks as
// memory-mapped peripherals: firmware (C, compiled to the hex images named
// by ROM_INIT / RAM_INIT) runs the P/PD/PID laws of eq. (20)-(22) and writes
// the PWM command of eq. (1).  The memory and register map is
// torqueloop/spec/regmap.toml; docs/soc.md describes the blocks.
//
// The board top (rtl/board/de0_cv_top.v) supplies clk and a synchronous
// reset (reset_sync) and wires the pins (tl_soc_board.vh); every
// asynchronous input is synchronised inside the fabric.
// the register map's TL_* names (generated; the include guard makes a second include empty)
`include "regmap.vh"
`include "tl_cpu_bus.vh"
`include "tl_soc_board.vh"
`default_nettype none

module tl_soc #(
    parameter integer RAM_BYTES        = `TL_RAM_SIZE,
    parameter         RAM_INIT         = "",
    parameter         ROM_INIT         = "",
    parameter [31:0]  BUILD_ID         = 32'd0,
    parameter integer CLK_HZ           = `TL_CLK_HZ,
    parameter [31:0]  HART_ID          = 32'd0,
    parameter integer LIMIT_DEBOUNCE_CLKS = 50_000,  // limit switch debounce, 1 ms
    // the CPU: 1 tl_cpu_pipe (pipelined, on a fabric that takes a request
    // every cycle: the board's), 0 tl_cpu (multi-cycle, smaller); docs/cpu.md
    parameter integer CPU_PIPELINED    = 1
) (
    input  wire        clk,
    input  wire        rst,            // synchronous, active high
    `SOC_BOARD_PORTS     // tl_soc_board.vh
);

    `CPU_BUS_WIRES
    /* verilator lint_off UNUSEDSIGNAL */
    wire        retire;   // instruction-retired pulse: for test benches (instruction counts)
    /* verilator lint_on UNUSEDSIGNAL */

    generate
        if (CPU_PIPELINED != 0) begin : g_pipe
            tl_cpu_pipe #(.RESET_PC(`TL_BOOT_ROM_BASE), .HART_ID(HART_ID)) u_cpu (
                `CPU_CORE_CONNECT
            );
        end else begin : g_multi
            tl_cpu #(.RESET_PC(`TL_BOOT_ROM_BASE), .HART_ID(HART_ID)) u_cpu (
                `CPU_CORE_CONNECT
            );
        end
    endgenerate

    tl_soc_fabric #(
        .RAM_BYTES(RAM_BYTES), .RAM_INIT(RAM_INIT), .ROM_INIT(ROM_INIT), .BUILD_ID(BUILD_ID),
        .CLK_HZ(CLK_HZ), .LIMIT_DEBOUNCE_CLKS(LIMIT_DEBOUNCE_CLKS), .PIPELINED(CPU_PIPELINED)
    ) u_fabric (
        .clk(clk), .rst(rst),
        `CPU_BUS_CONNECT, `CPU_IRQ_CONNECT,
        `SOC_BOARD_CONNECT
    );

endmodule

`default_nettype wire
