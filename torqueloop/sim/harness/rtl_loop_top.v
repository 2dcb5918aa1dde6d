// SPDX-License-Identifier: MIT
// rtl_loop_top: the board image (rtl/board/de0_cv_top.v) as the co-simulation
// sees it - only the pins a bench of the real machine would touch, as plain
// ports (no inouts), so the same wrapper serves the cocotb harness and the
// native Verilator harness (torqueloop/sim/harness/harness.cpp).  Which header bit
// carries what is de0_cv_cable's business (torqueloop/sim/harness/de0_cv_cable.v, generated from
// constraints/pins.toml: the cable harness of docs/hardware.md, GPIO_0 =
// axis x, GPIO_1 = axis z).
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
    input  wire [1:0] lim_neg,      // limit switches, 1 = open (tripped); 0 = closed (NC switch to GND)
    input  wire [1:0] lim_pos,
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

    /* verilator lint_off UNUSEDSIGNAL */
    wire        rnxv_cts_n;   // the FPGA's RTS: the co-simulated host never holds back
    /* verilator lint_on UNUSEDSIGNAL */
    de0_cv_cable u_cable (
        .GPIO_0(GPIO_0), .GPIO_1(GPIO_1), .ibt2_rpwm_pin(rpwm), .ibt2_lpwm_pin(lpwm),
        .ibt2_r_en_pin(r_en), .ibt2_l_en_pin(l_en), .ibt2_fault_n_pin(fault_n), .enc_a_pin(enc_a),
        .enc_b_pin(enc_b), .enc_z_pin(enc_z), .lim_neg_pin(lim_neg), .lim_pos_pin(lim_pos),
        .uart_rx_pin(host_tx), .uart_tx_pin(host_rx),
        .uart_cts_n_pin(1'b0), .uart_rts_n_pin(rnxv_cts_n)   // RN-XV RTS low: the FPGA may always send
    );
endmodule

`default_nettype wire
