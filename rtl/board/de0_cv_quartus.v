// SPDX-License-Identifier: MIT
// de0_cv_quartus: the Quartus top-level entity of the Terasic DE0-CV project, generated from constraints/pins.toml by torqueloop.flow.generate;
// edit there.  It is the board top, rtl/board/de0_cv_top.v, with the boot memory
// images as string parameters in Verilog (paths from the Quartus project folder,
// where $readmemh looks), since the .qsf's set_parameter is documented only for numbers,
// and the pin table's [top_parameters] beside them.
`default_nettype none

module de0_cv_quartus (
    input wire CLOCK_50, input wire RESET_N, input wire [3:0] KEY, input wire [9:0] SW,
    output wire [9:0] LEDR, output wire [6:0] HEX0, output wire [6:0] HEX1, output wire [6:0] HEX2,
    output wire [6:0] HEX3, output wire [6:0] HEX4, output wire [6:0] HEX5, inout wire [35:0] GPIO_0,
    inout wire [35:0] GPIO_1
);

    de0_cv_top #(.ROM_INIT("../firmware/boot/boot_rom.hex"), .BRIDGE_FAULT_WIRED(3), .FLASH_ASMI(1)) u_top (
        .CLOCK_50(CLOCK_50), .RESET_N(RESET_N), .KEY(KEY), .SW(SW), .LEDR(LEDR), .HEX0(HEX0), .HEX1(HEX1), .HEX2(HEX2), .HEX3(HEX3), .HEX4(HEX4), .HEX5(HEX5), .GPIO_0(GPIO_0), .GPIO_1(GPIO_1)
    );

endmodule

`default_nettype wire
