// SPDX-License-Identifier: MIT
// de0_cv_cable: the cable harness of docs/hardware.md in Verilog, for the board's test
// wrappers; generated from constraints/pins.toml by torqueloop.flow.generate; edit there.
// Each header signal meets a port named as the board top's own net.
`default_nettype none

module de0_cv_cable (
    inout  wire [35:0] GPIO_0,
    inout  wire [35:0] GPIO_1,
    output wire [1:0]  ibt2_rpwm_pin,    // FPGA drives it
    output wire [1:0]  ibt2_lpwm_pin,    // FPGA drives it
    output wire [1:0]  ibt2_r_en_pin,    // FPGA drives it
    output wire [1:0]  ibt2_l_en_pin,    // FPGA drives it
    input  wire [1:0]  ibt2_fault_n_pin, // FPGA reads it
    input  wire [1:0]  enc_a_pin,        // FPGA reads it
    input  wire [1:0]  enc_b_pin,        // FPGA reads it
    input  wire [1:0]  enc_z_pin,        // FPGA reads it
    input  wire [1:0]  lim_neg_pin,      // FPGA reads it
    input  wire [1:0]  lim_pos_pin,      // FPGA reads it
    input  wire        uart_rx_pin,      // FPGA reads it
    output wire        uart_tx_pin,      // FPGA drives it
    input  wire        uart_cts_n_pin,   // FPGA reads it
    output wire        uart_rts_n_pin    // FPGA drives it
);
    assign ibt2_rpwm_pin[0]    = GPIO_0[0];           // pin 1: IBT-2 #1 (axis 1) RPWM
    assign ibt2_lpwm_pin[0]    = GPIO_0[1];           // pin 2: IBT-2 #1 (axis 1) LPWM
    assign ibt2_r_en_pin[0]    = GPIO_0[2];           // pin 3: IBT-2 #1 (axis 1) R_EN
    assign ibt2_l_en_pin[0]    = GPIO_0[3];           // pin 4: IBT-2 #1 (axis 1) L_EN
    assign GPIO_0[4]           = ibt2_fault_n_pin[0]; // pin 5: IBT-2 #1 (axis 1) R_IS, L_IS via comparators
    assign GPIO_0[5]           = lim_neg_pin[0];      // pin 6: limit switches (axis 1) negative-end switch
    assign GPIO_0[6]           = enc_a_pin[0];        // pin 7: encoder 1 (axis 1) A
    assign GPIO_0[7]           = enc_b_pin[0];        // pin 8: encoder 1 (axis 1) B
    assign GPIO_0[8]           = enc_z_pin[0];        // pin 9: encoder 1 (axis 1) Z
    assign GPIO_0[9]           = lim_pos_pin[0];      // pin 10: limit switches (axis 1) positive-end switch
    assign GPIO_0[10]          = uart_rx_pin;         // pin 13: RN-XV TX (XBee pin 2)
    assign uart_tx_pin         = GPIO_0[11];          // pin 14: RN-XV RX (XBee pin 3)
    assign GPIO_0[12]          = uart_cts_n_pin;      // pin 15: RN-XV RTS (XBee pin 16)
    assign uart_rts_n_pin      = GPIO_0[13];          // pin 16: RN-XV CTS (XBee pin 12)
    assign ibt2_rpwm_pin[1]    = GPIO_1[0];           // pin 1: IBT-2 #2 (axis 2) RPWM
    assign ibt2_lpwm_pin[1]    = GPIO_1[1];           // pin 2: IBT-2 #2 (axis 2) LPWM
    assign ibt2_r_en_pin[1]    = GPIO_1[2];           // pin 3: IBT-2 #2 (axis 2) R_EN
    assign ibt2_l_en_pin[1]    = GPIO_1[3];           // pin 4: IBT-2 #2 (axis 2) L_EN
    assign GPIO_1[4]           = ibt2_fault_n_pin[1]; // pin 5: IBT-2 #2 (axis 2) R_IS, L_IS via comparators
    assign GPIO_1[5]           = lim_neg_pin[1];      // pin 6: limit switches (axis 2) negative-end switch
    assign GPIO_1[6]           = enc_a_pin[1];        // pin 7: encoder 2 (axis 2) A
    assign GPIO_1[7]           = enc_b_pin[1];        // pin 8: encoder 2 (axis 2) B
    assign GPIO_1[8]           = enc_z_pin[1];        // pin 9: encoder 2 (axis 2) Z
    assign GPIO_1[9]           = lim_pos_pin[1];      // pin 10: limit switches (axis 2) positive-end switch
endmodule

`default_nettype wire
