// SPDX-License-Identifier: MIT
// Test harness of the board top: the cable harness of docs/hardware.md in
// Verilog.  It drives the board's input pins and the header pins the
// IBT-2s, encoders and RN-XV would drive, and brings every FPGA output out
// as a plain port, so cocotb never touches an inout.  The GPIO indices are
// written here by hand from the wiring table (not generated from
// constraints/pins.toml), as a second statement of the same wiring.
// Every header input is driven here (push-pull; Verilator is two-state and
// has no pull-ups), so the spare pins are the only undriven ones: on a
// four-state simulator the bench checks that they float (z).
`default_nettype none

module de0_cv_top_tb #(
    parameter         ROM_INIT  = "",
    parameter         RAM_INIT  = "",
    parameter integer RAM_BYTES = 4096
) (
    input  wire       clk,
    input  wire       reset_n,
    input  wire [3:0] key,          // active low, as on the board
    input  wire [9:0] sw,
    output wire [9:0] ledr,
    output wire [41:0] hex,         // {HEX5, ..., HEX0}
    // per axis, index = axis (axis 1 on GPIO_0, axis 2 on GPIO_1)
    output wire [1:0] rpwm,
    output wire [1:0] lpwm,
    output wire [1:0] r_en,
    output wire [1:0] l_en,
    input  wire [1:0] fault_n,      // comparator outputs, low = fault
    input  wire [1:0] enc_a,
    input  wire [1:0] enc_b,
    input  wire [1:0] enc_z,
    // RN-XV side of the UART
    input  wire       rnxv_tx,      // into the FPGA
    output wire       rnxv_rx,      // out of the FPGA
    input  wire       rnxv_rts,     // into the FPGA's CTS, low = FPGA may send
    output wire       rnxv_cts,     // the FPGA's RTS, low = RN-XV may send
    // every header pin the design should leave alone, for a check that it does
    output wire [35:0] gpio0_pins,
    output wire [35:0] gpio1_pins
);
    wire [35:0] GPIO_0;
    wire [35:0] GPIO_1;

    de0_cv_top #(.ROM_INIT(ROM_INIT), .RAM_INIT(RAM_INIT), .RAM_BYTES(RAM_BYTES)) dut (
        .CLOCK_50(clk), .RESET_N(reset_n), .KEY(key), .SW(sw), .LEDR(ledr),
        .HEX0(hex[6:0]), .HEX1(hex[13:7]), .HEX2(hex[20:14]),
        .HEX3(hex[27:21]), .HEX4(hex[34:28]), .HEX5(hex[41:35]),
        .GPIO_0(GPIO_0), .GPIO_1(GPIO_1)
    );

    // header pins 1-4: IBT-2 RPWM, LPWM, R_EN, L_EN
    assign rpwm = {GPIO_1[0], GPIO_0[0]};
    assign lpwm = {GPIO_1[1], GPIO_0[1]};
    assign r_en = {GPIO_1[2], GPIO_0[2]};
    assign l_en = {GPIO_1[3], GPIO_0[3]};
    // header pin 5: fault comparator output (low = fault)
    assign GPIO_0[4] = fault_n[0];
    assign GPIO_1[4] = fault_n[1];
    // header pins 7-9: encoder A, B, Z
    assign GPIO_0[6] = enc_a[0];
    assign GPIO_1[6] = enc_a[1];
    assign GPIO_0[7] = enc_b[0];
    assign GPIO_1[7] = enc_b[1];
    assign GPIO_0[8] = enc_z[0];
    assign GPIO_1[8] = enc_z[1];
    // GPIO_0 header pins 13-16: RN-XV TX, RX, RTS, CTS
    assign GPIO_0[10] = rnxv_tx;
    assign rnxv_rx    = GPIO_0[11];
    assign GPIO_0[12] = rnxv_rts;
    assign rnxv_cts   = GPIO_0[13];

    assign gpio0_pins = GPIO_0;
    assign gpio1_pins = GPIO_1;
endmodule

`default_nettype wire
