// SPDX-License-Identifier: MIT
// The SoC's board-side ports, written once for tl_soc and tl_soc_fabric (the
// fabric has them all; the SoC passes them through):
//   ledr, sw, key_n, hex0_n..hex5_n   DE0-CV LEDs, switches, keys, 7-segment digits
//   rpwm, lpwm, r_en, l_en            two IBT-2 bridges, index = axis
//   pwm, dir                          PWM+DIR mode (PWM_CTRL.DIR_MODE = 1)
//   bridge_fault                      asynchronous, 1 = fault (comparator on R_IS/L_IS); tie 0 if absent
//   enc_a, enc_b, enc_z               two encoders
//   uart_rx, uart_tx, uart_cts_n, uart_rts_n   UART to the RN-XV
//   estop                             e-stop, asynchronous, 1 = stop
//   lim_neg, lim_pos                  limit switches, asynchronous, 1 = open (tripped or wire broken), per axis
//   wdog_alive                        the hardware watchdog armed and not expired (the board's drive
//                                     interlock arms only then)
//   flash_dclk, flash_ncs, flash_mosi, flash_miso   configuration flash, SPI mode 0 (FLASH page;
//                                     the board reaches it through the ASMI block)
// Every asynchronous input is synchronised inside the fabric.  Macros, not
// module items: a port list cannot come from anything else.
`ifndef TL_SOC_BOARD_VH
`define TL_SOC_BOARD_VH

`define SOC_BOARD_PORTS \
    output wire [9:0]  ledr, \
    input  wire [9:0]  sw, \
    input  wire [3:0]  key_n, \
    output wire [6:0]  hex0_n, \
    output wire [6:0]  hex1_n, \
    output wire [6:0]  hex2_n, \
    output wire [6:0]  hex3_n, \
    output wire [6:0]  hex4_n, \
    output wire [6:0]  hex5_n, \
    output wire [1:0]  rpwm, \
    output wire [1:0]  lpwm, \
    output wire [1:0]  r_en, \
    output wire [1:0]  l_en, \
    output wire [1:0]  pwm, \
    output wire [1:0]  dir, \
    input  wire [1:0]  bridge_fault, \
    input  wire [1:0]  enc_a, \
    input  wire [1:0]  enc_b, \
    input  wire [1:0]  enc_z, \
    input  wire        uart_rx, \
    output wire        uart_tx, \
    input  wire        uart_cts_n, \
    output wire        uart_rts_n, \
    input  wire        estop, \
    input  wire [1:0]  lim_neg, \
    input  wire [1:0]  lim_pos, \
    output wire        wdog_alive, \
    output wire        flash_dclk, \
    output wire        flash_ncs, \
    output wire        flash_mosi, \
    input  wire        flash_miso

// Named connections of those ports to the signals of the same names.
`define SOC_BOARD_CONNECT \
    .ledr(ledr), .sw(sw), .key_n(key_n), \
    .hex0_n(hex0_n), .hex1_n(hex1_n), .hex2_n(hex2_n), .hex3_n(hex3_n), .hex4_n(hex4_n), .hex5_n(hex5_n), \
    .rpwm(rpwm), .lpwm(lpwm), .r_en(r_en), .l_en(l_en), .pwm(pwm), .dir(dir), \
    .bridge_fault(bridge_fault), .enc_a(enc_a), .enc_b(enc_b), .enc_z(enc_z), \
    .uart_rx(uart_rx), .uart_tx(uart_tx), .uart_cts_n(uart_cts_n), .uart_rts_n(uart_rts_n), \
    .estop(estop), .lim_neg(lim_neg), .lim_pos(lim_pos), .wdog_alive(wdog_alive), \
    .flash_dclk(flash_dclk), .flash_ncs(flash_ncs), .flash_mosi(flash_mosi), .flash_miso(flash_miso)

`endif
