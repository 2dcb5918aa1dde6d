// SPDX-License-Identifier: MIT
// de0_cv_top: the torqueloop SoC on the Terasic DE0-CV (Cyclone V 5CEBA4F23C7N).
//
// Port names are Terasic's, so constraints/de0_cv_top.qsf assigns each bit
// to the board pin of the same name.  What each GPIO header pin carries is
// defined once, in constraints/pins.toml; the "GPIO header map" block below
// is generated from it (torqueloop.flow.generate) and checked by
// python -m torqueloop.flow constraints, together with every pin, I/O standard and
// the timing constraints.  Wiring to the IBT-2 modules, the encoders and
// the RN-XV: docs/hardware.md.
//
// Around the SoC (rtl/soc/tl_soc.v) this adds only what is board-specific:
//   - RESET_N through reset_sync (asynchronous assertion, synchronous release);
//   - drive_interlock between the SoC's bridge outputs and the IBT-2 pins: the
//     drives run only after SW[0] has been moved up (with no stop, no fault
//     present and the SoC's hardware watchdog alive) and stop at once on
//     KEY[0], a bridge fault or a watchdog expiry, independently of the
//     processor and of the SoC's own safety latch (SYS.SAFETY);
//   - estop_gate after it: KEY[0] forces every bridge input low through one
//     AND gate, without the clock (the interlock's outputs are registered);
//   - the limit switches (header pins 6 and 10 of each axis) to the SoC;
//   - KEY[0] as the e-stop input of the SoC as well (active high there);
//   - LEDR[9] = drives armed, LEDR[8] = stop or fault since the last arming;
//     LEDR[7:0], HEX0-HEX5 belong to the firmware (GPIO registers);
//   - config_flash between the SoC's flash port and the EPCS64: the Cyclone V's
//     ASMI block when FLASH_ASMI = 1 (the Quartus top), else a simulator's
//     flash model at that block's ports (rtl/board/tl_config_flash.v).
// The SoC synchronises every board input it reads (KEY, SW, encoders, UART,
// e-stop, faults); the interlock's own inputs go through sync_2ff here.
// The SoC's PWM+DIR outputs (for bridges with a direction input) are not
// used on the IBT-2 and not brought out.
// the register map's TL_* names (generated; the include guard makes a second include empty)
`include "regmap.vh"
`default_nettype none

module de0_cv_top #(
    parameter         ROM_INIT  = "",             // boot ROM image ($readmemh, one 32-bit word per line)
    parameter         RAM_INIT  = "",             // RAM image; empty when the program arrives over the UART
    parameter integer RAM_BYTES = `TL_RAM_SIZE,   // smaller only for quick generic synthesis checks
    // Bit n: axis n+1's bridge-fault comparator is wired (1) or not fitted (0:
    // that fault pin is ignored).  Wired, the comparator holds the line low
    // while the bridge is healthy, so an open line - a broken wire, an
    // unpowered comparator - reads as a fault (the FPGA's weak pull-up).
    parameter [1:0]   BRIDGE_FAULT_WIRED = 2'b11,
    // 1: the configuration flash through the Cyclone V's ASMI block (set by the
    // Quartus top, constraints/pins.toml [top_parameters]); 0: the flash lines end
    // at u_flash's ports for a simulator's flash model (tl_config_flash.v)
    parameter integer FLASH_ASMI = 0
) (
    input  wire        CLOCK_50,
    input  wire        RESET_N,
    input  wire [3:0]  KEY,
    input  wire [9:0]  SW,
    output wire [9:0]  LEDR,
    output wire [6:0]  HEX0,
    output wire [6:0]  HEX1,
    output wire [6:0]  HEX2,
    output wire [6:0]  HEX3,
    output wire [6:0]  HEX4,
    output wire [6:0]  HEX5,
    inout  wire [35:0] GPIO_0,
    inout  wire [35:0] GPIO_1
);

    localparam integer AXES = 2;

    // CLOCK_50 drives everything, and the SoC derives its baud rate, PWM
    // carrier and timer from its CLK_HZ (regmap: `TL_CLK_HZ): they must agree.
    // A mismatch instantiates a module that does not exist, so elaboration
    // stops with its name as the message.
    generate
        if (`TL_CLK_HZ != 50_000_000) begin : g_clk_check
            tl_clk_hz_is_not_the_de0_cv_50_mhz u_clk_check ();
        end
    endgenerate

    wire clk = CLOCK_50;
    wire rst;

    tl_reset_sync #(.STAGES(2)) u_reset_sync (.clk(clk), .arst_n(RESET_N), .rst_out(rst));

    // ---- raw pin-level nets of the GPIO headers (unsynchronised) ----
    wire [AXES-1:0] ibt2_rpwm_pin;
    wire [AXES-1:0] ibt2_lpwm_pin;
    wire [AXES-1:0] ibt2_r_en_pin;
    wire [AXES-1:0] ibt2_l_en_pin;
    wire [AXES-1:0] ibt2_fault_pin;     // comparator outputs, 1 = fault (open: pulled up = fault)
    wire [AXES-1:0] enc_a_pin;
    wire [AXES-1:0] enc_b_pin;
    wire [AXES-1:0] enc_z_pin;
    wire            uart_rx_pin;
    wire            uart_tx_pin;
    wire            uart_cts_n_pin;
    wire            uart_rts_n_pin;
    wire [AXES-1:0] lim_neg_pin;        // limit switches, NC to GND: 1 = open (tripped or wire broken)
    wire [AXES-1:0] lim_pos_pin;
    wire            wdog_alive;         // the SoC's hardware watchdog armed and fed

    // ---- the SoC ----
    /* verilator lint_off UNUSEDSIGNAL */
    wire [9:0]      soc_ledr;           // [9:8] give way to the interlock's state
    /* verilator lint_on UNUSEDSIGNAL */
    wire [AXES-1:0] soc_rpwm, soc_lpwm, soc_r_en, soc_l_en;
    /* verilator lint_off UNUSEDSIGNAL */
    wire [AXES-1:0] soc_pwm, soc_dir;   // PWM+DIR mode: no IBT-2 input for it
    /* verilator lint_on UNUSEDSIGNAL */
    wire            flash_dclk, flash_ncs, flash_mosi, flash_miso;   // the SoC's configuration-flash port

    tl_soc #(
        .RAM_BYTES(RAM_BYTES),
        .ROM_INIT(ROM_INIT),
        .RAM_INIT(RAM_INIT)
    ) u_soc (
        .clk(clk),
        .rst(rst),
        .ledr(soc_ledr),
        .sw(SW),
        .key_n(KEY),
        .hex0_n(HEX0),
        .hex1_n(HEX1),
        .hex2_n(HEX2),
        .hex3_n(HEX3),
        .hex4_n(HEX4),
        .hex5_n(HEX5),
        .rpwm(soc_rpwm),
        .lpwm(soc_lpwm),
        .r_en(soc_r_en),
        .l_en(soc_l_en),
        .pwm(soc_pwm),
        .dir(soc_dir),
        .bridge_fault(ibt2_fault_pin & BRIDGE_FAULT_WIRED),
        .enc_a(enc_a_pin),
        .enc_b(enc_b_pin),
        .enc_z(enc_z_pin),
        .uart_rx(uart_rx_pin),
        .uart_tx(uart_tx_pin),
        .uart_cts_n(uart_cts_n_pin),
        .uart_rts_n(uart_rts_n_pin),
        .estop(~KEY[0]),
        .lim_neg(lim_neg_pin),
        .lim_pos(lim_pos_pin),
        .wdog_alive(wdog_alive),
        .flash_dclk(flash_dclk),
        .flash_ncs(flash_ncs),
        .flash_mosi(flash_mosi),
        .flash_miso(flash_miso)
    );

    // ---- the configuration flash (EPCS64): the parameter store's sectors ----
    tl_config_flash #(.ASMI(FLASH_ASMI)) u_flash (
        .flash_dclk(flash_dclk),
        .flash_ncs(flash_ncs),
        .flash_mosi(flash_mosi),
        .flash_miso(flash_miso)
    );

    // ---- board-level drive interlock ----
    // Reset values: key released (1), no fault (0), and the arm switch UP (1):
    // a switch already up when reset ends must not look like a fresh up-move
    // (a 0 here would make a false rising edge two clocks after reset and arm
    // the drives - tb/de0_cv_top caught exactly that).
    wire            estop_n_s;
    wire            arm_sw_s;
    wire [AXES-1:0] fault_s;
    wire            armed, tripped;
    /* verilator lint_off UNUSEDSIGNAL */
    wire [AXES-1:0] fault_latched;      // for a future status register; LEDR[8] shows the sum
    /* verilator lint_on UNUSEDSIGNAL */

    tl_sync_2ff #(.WIDTH(1), .RESET_VAL(1)) u_sync_estop (
        .clk(clk), .rst(rst), .async_in(KEY[0]), .sync_out(estop_n_s));
    tl_sync_2ff #(.WIDTH(1), .RESET_VAL(1)) u_sync_arm (
        .clk(clk), .rst(rst), .async_in(SW[0]), .sync_out(arm_sw_s));
    tl_sync_2ff #(.WIDTH(AXES), .RESET_VAL(0)) u_sync_fault (
        .clk(clk), .rst(rst), .async_in(ibt2_fault_pin & BRIDGE_FAULT_WIRED), .sync_out(fault_s));

    wire [AXES-1:0] il_rpwm, il_lpwm, il_r_en, il_l_en;   // the interlock's registered outputs
    tl_drive_interlock #(.AXES(AXES), .FAULT_FILTER_CLKS(250)) u_interlock (
        .clk(clk),
        .rst(rst),
        .estop(~estop_n_s),
        .arm_sw(arm_sw_s),
        .fault(fault_s),
        .alive(wdog_alive),
        .rpwm_in(soc_rpwm),
        .lpwm_in(soc_lpwm),
        .r_en_in(soc_r_en),
        .l_en_in(soc_l_en),
        .rpwm_out(il_rpwm),
        .lpwm_out(il_lpwm),
        .r_en_out(il_r_en),
        .l_en_out(il_l_en),
        .armed(armed),
        .tripped(tripped),
        .fault_latched(fault_latched)
    );

    // ---- KEY[0] to the pins without the clock: one AND gate per bridge input ----
    tl_estop_gate #(.N(4 * AXES)) u_estop_gate (
        .key_n(KEY[0]),
        .drive_in({il_l_en, il_r_en, il_lpwm, il_rpwm}),
        .drive_out({ibt2_l_en_pin, ibt2_r_en_pin, ibt2_lpwm_pin, ibt2_rpwm_pin})
    );

    assign LEDR = {armed, tripped, soc_ledr[7:0]};

    // ---- GPIO header map: generated from constraints/pins.toml by torqueloop.flow.generate; edit there ----
    assign GPIO_0[0]           = ibt2_rpwm_pin[0];    // pin 1: IBT-2 #1 (axis 1) RPWM
    assign GPIO_0[1]           = ibt2_lpwm_pin[0];    // pin 2: IBT-2 #1 (axis 1) LPWM
    assign GPIO_0[2]           = ibt2_r_en_pin[0];    // pin 3: IBT-2 #1 (axis 1) R_EN
    assign GPIO_0[3]           = ibt2_l_en_pin[0];    // pin 4: IBT-2 #1 (axis 1) L_EN
    assign GPIO_0[4]           = 1'bz;                // pin 5: input
    assign ibt2_fault_pin[0]   = GPIO_0[4];           // pin 5: IBT-2 #1 (axis 1) R_IS, L_IS via comparators
    assign GPIO_0[5]           = 1'bz;                // pin 6: input
    assign lim_neg_pin[0]      = GPIO_0[5];           // pin 6: limit switches (axis 1) negative-end switch
    assign GPIO_0[6]           = 1'bz;                // pin 7: input
    assign enc_a_pin[0]        = GPIO_0[6];           // pin 7: encoder 1 (axis 1) A
    assign GPIO_0[7]           = 1'bz;                // pin 8: input
    assign enc_b_pin[0]        = GPIO_0[7];           // pin 8: encoder 1 (axis 1) B
    assign GPIO_0[8]           = 1'bz;                // pin 9: input
    assign enc_z_pin[0]        = GPIO_0[8];           // pin 9: encoder 1 (axis 1) Z
    assign GPIO_0[9]           = 1'bz;                // pin 10: input
    assign lim_pos_pin[0]      = GPIO_0[9];           // pin 10: limit switches (axis 1) positive-end switch
    assign GPIO_0[10]          = 1'bz;                // pin 13: input
    assign uart_rx_pin         = GPIO_0[10];          // pin 13: RN-XV TX (XBee pin 2)
    assign GPIO_0[11]          = uart_tx_pin;         // pin 14: RN-XV RX (XBee pin 3)
    assign GPIO_0[12]          = 1'bz;                // pin 15: input
    assign uart_cts_n_pin      = GPIO_0[12];          // pin 15: RN-XV RTS (XBee pin 16)
    assign GPIO_0[13]          = uart_rts_n_pin;      // pin 16: RN-XV CTS (XBee pin 12)
    assign GPIO_0[25:14]       = {12{1'bz}};          // pins 17-28: spare, tri-stated
    assign GPIO_0[35:26]       = {10{1'bz}};          // pins 31-40: spare, tri-stated
    assign GPIO_1[0]           = ibt2_rpwm_pin[1];    // pin 1: IBT-2 #2 (axis 2) RPWM
    assign GPIO_1[1]           = ibt2_lpwm_pin[1];    // pin 2: IBT-2 #2 (axis 2) LPWM
    assign GPIO_1[2]           = ibt2_r_en_pin[1];    // pin 3: IBT-2 #2 (axis 2) R_EN
    assign GPIO_1[3]           = ibt2_l_en_pin[1];    // pin 4: IBT-2 #2 (axis 2) L_EN
    assign GPIO_1[4]           = 1'bz;                // pin 5: input
    assign ibt2_fault_pin[1]   = GPIO_1[4];           // pin 5: IBT-2 #2 (axis 2) R_IS, L_IS via comparators
    assign GPIO_1[5]           = 1'bz;                // pin 6: input
    assign lim_neg_pin[1]      = GPIO_1[5];           // pin 6: limit switches (axis 2) negative-end switch
    assign GPIO_1[6]           = 1'bz;                // pin 7: input
    assign enc_a_pin[1]        = GPIO_1[6];           // pin 7: encoder 2 (axis 2) A
    assign GPIO_1[7]           = 1'bz;                // pin 8: input
    assign enc_b_pin[1]        = GPIO_1[7];           // pin 8: encoder 2 (axis 2) B
    assign GPIO_1[8]           = 1'bz;                // pin 9: input
    assign enc_z_pin[1]        = GPIO_1[8];           // pin 9: encoder 2 (axis 2) Z
    assign GPIO_1[9]           = 1'bz;                // pin 10: input
    assign lim_pos_pin[1]      = GPIO_1[9];           // pin 10: limit switches (axis 2) positive-end switch
    assign GPIO_1[25:10]       = {16{1'bz}};          // pins 13-28: spare, tri-stated
    assign GPIO_1[35:26]       = {10{1'bz}};          // pins 31-40: spare, tri-stated
    // ---- end of the generated GPIO header map ----

endmodule

`default_nettype wire
