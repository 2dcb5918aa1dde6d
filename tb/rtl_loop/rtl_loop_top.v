// SPDX-License-Identifier: MIT
// rtl_loop_top: the board image (rtl/board/de0_cv_top.v) as the co-simulation
// sees it - only the pins a bench of the real machine would touch, as plain
// ports (no inouts), so the same wrapper serves the cocotb harness and the
// native Verilator harness (tb/rtl_loop/native).  The GPIO indices follow the
// cable harness of docs/hardware.md (GPIO_0 = axis x, GPIO_1 = axis z).
// Nothing inside the SoC is brought out: the plant sees the bridge pins and
// drives the encoder pins, the host sees the UART pins, as on the board.
`default_nettype none

module rtl_loop_top #(
    parameter         ROM_INIT = "",
    parameter         RAM_INIT = ""
) (
    input  wire       clk,
    input  wire       reset_n,
    input  wire       key0_n,       // e-stop button, active low
    input  wire       sw0,          // drive arm switch: a rising edge arms the interlock
    input  wire [1:0] fault_n,      // IBT-2 fault comparators, low = fault
    input  wire [1:0] enc_a,
    input  wire [1:0] enc_b,
    input  wire [1:0] enc_z,
    input  wire       host_tx,      // RN-XV TX -> FPGA UART RX
    output wire       host_rx,      // FPGA UART TX -> RN-XV RX
    output wire [1:0] rpwm,
    output wire [1:0] lpwm,
    output wire [1:0] r_en,
    output wire [1:0] l_en
);
    wire [35:0] GPIO_0;
    wire [35:0] GPIO_1;
    /* verilator lint_off UNUSEDSIGNAL */
    wire [9:0]  ledr;
    wire [41:0] hex;
    /* verilator lint_on UNUSEDSIGNAL */

    de0_cv_top #(.ROM_INIT(ROM_INIT), .RAM_INIT(RAM_INIT)) dut (
        .CLOCK_50(clk), .RESET_N(reset_n), .KEY({3'b111, key0_n}), .SW({9'd0, sw0}), .LEDR(ledr),
        .HEX0(hex[6:0]), .HEX1(hex[13:7]), .HEX2(hex[20:14]),
        .HEX3(hex[27:21]), .HEX4(hex[34:28]), .HEX5(hex[41:35]),
        .GPIO_0(GPIO_0), .GPIO_1(GPIO_1)
    );

    // header pins 1-4: IBT-2 RPWM, LPWM, R_EN, L_EN
    assign rpwm = {GPIO_1[0], GPIO_0[0]};
    assign lpwm = {GPIO_1[1], GPIO_0[1]};
    assign r_en = {GPIO_1[2], GPIO_0[2]};
    assign l_en = {GPIO_1[3], GPIO_0[3]};
    // header pin 5: fault comparators; pins 7-9: encoder A, B, Z
    assign GPIO_0[4] = fault_n[0];
    assign GPIO_1[4] = fault_n[1];
    assign GPIO_0[6] = enc_a[0];
    assign GPIO_1[6] = enc_a[1];
    assign GPIO_0[7] = enc_b[0];
    assign GPIO_1[7] = enc_b[1];
    assign GPIO_0[8] = enc_z[0];
    assign GPIO_1[8] = enc_z[1];
    // GPIO_0 pins 13-16: RN-XV TX, RX, RTS (low: the FPGA may send), CTS
    assign GPIO_0[10] = host_tx;
    assign host_rx    = GPIO_0[11];
    assign GPIO_0[12] = 1'b0;
endmodule

`default_nettype wire
