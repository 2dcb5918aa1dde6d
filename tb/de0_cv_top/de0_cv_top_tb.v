// SPDX-License-Identifier: MIT
// Test harness of the board top: the cable harness of docs/hardware.md in
// Verilog.  It drives the board's input pins and the header pins the
// IBT-2s, encoders and RN-XV would drive, and brings every FPGA output out
// as a plain port, so cocotb never touches an inout.  Which header bit
// carries what is de0_cv_cable's business (generated from
// constraints/pins.toml, the mirror of the board top's own GPIO block).
// Every header input is driven (push-pull; Verilator is two-state and has
// no pull-ups), so the spare pins are the only undriven ones: on a
// four-state simulator the bench checks that they float (z).  The
// exceptions are the bridge-fault lines, which the bench can leave open
// (fault_open: a broken wire, no comparator): they carry the FPGA's weak
// pull-up (constraints/pins.toml), so an open one reads 1.
`default_nettype none

module de0_cv_top_tb #(
    parameter         ROM_INIT  = "",
    parameter         RAM_INIT  = "",
    parameter integer RAM_BYTES = 4096,
    parameter [1:0]   BRIDGE_FAULT_WIRED = 2'b11
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
    input  wire [1:0] fault,        // comparator lines: 0 = held low (healthy), 1 = released (fault)
    input  wire [1:0] fault_open,   // 1 = that line is open: nothing drives it
    input  wire [1:0] enc_a,
    input  wire [1:0] enc_b,
    input  wire [1:0] enc_z,
    input  wire [1:0] lim_neg,      // limit switches, 1 = open (tripped); 0 = closed (NC switch to GND)
    input  wire [1:0] lim_pos,
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

    wire [1:0] fault_line = {fault_open[1] ? 1'bz : fault[1], fault_open[0] ? 1'bz : fault[0]};
    pullup (GPIO_0[4]);   // the FPGA's weak pull-ups on the fault pins (header pin 5)
    pullup (GPIO_1[4]);

    de0_cv_top #(.ROM_INIT(ROM_INIT), .RAM_INIT(RAM_INIT), .RAM_BYTES(RAM_BYTES),
                 .BRIDGE_FAULT_WIRED(BRIDGE_FAULT_WIRED)) dut (
        .CLOCK_50(clk), .RESET_N(reset_n), .KEY(key), .SW(sw), .LEDR(ledr),
        .HEX0(hex[6:0]), .HEX1(hex[13:7]), .HEX2(hex[20:14]),
        .HEX3(hex[27:21]), .HEX4(hex[34:28]), .HEX5(hex[41:35]),
        .GPIO_0(GPIO_0), .GPIO_1(GPIO_1)
    );

    de0_cv_cable u_cable (
        .GPIO_0(GPIO_0), .GPIO_1(GPIO_1), .ibt2_rpwm_pin(rpwm), .ibt2_lpwm_pin(lpwm),
        .ibt2_r_en_pin(r_en), .ibt2_l_en_pin(l_en), .ibt2_fault_pin(fault_line), .enc_a_pin(enc_a),
        .enc_b_pin(enc_b), .enc_z_pin(enc_z), .lim_neg_pin(lim_neg), .lim_pos_pin(lim_pos),
        .uart_rx_pin(rnxv_tx), .uart_tx_pin(rnxv_rx),
        .uart_cts_n_pin(rnxv_rts), .uart_rts_n_pin(rnxv_cts)
    );

    assign gpio0_pins = GPIO_0;
    assign gpio1_pins = GPIO_1;
endmodule

`default_nettype wire
