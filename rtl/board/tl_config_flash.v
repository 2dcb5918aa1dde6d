// SPDX-License-Identifier: MIT
// tl_config_flash: where the SoC's configuration-flash port (tl_soc_flash:
// DCLK, chip select, data out, data in; SPI mode 0) meets the flash.
//
// On the DE0-CV the EPCS64 hangs on the Cyclone V's dedicated active-serial
// pins (DCLK, nCSO, AS_DATA0 = the flash's ASDI, AS_DATA1 = its DATA), which
// user logic reaches only through the device's ASMI block, the
// cyclonev_asmiblock primitive (Intel, AN 720 "Simulating the ASMI Block in
// Your Design", "Signals for ASMI Block" and "WYSIWYG for ASMI Block").  The
// connection, from that interface:
//   dclk      <- our DCLK (idles low, 12.5 MHz)
//   sce       <- our chip select, active low as the nCSO pin
//   oe        <- 0: active low, DCLK and nCSO reach the flash
//   data0out  <- our data out, to the flash's ASDI; data0oe = 1 (driven)
//   data1in   -> our data in, from the flash's DATA; data1oe = 0 (an input)
//   data1out = 0, data2out = data3out = 1 (AN 720's values for an EPCS, one
//   data line; pins 2 and 3 held high), data2oe = data3oe = 1.
//
// ASMI = 1 builds that (the Quartus top sets it: constraints/pins.toml
// [top_parameters]).  The primitive exists only inside Quartus; the linters
// read its interface from rtl/lint_only/cyclonev_asmiblock.v, which no
// simulation and no Quartus project compiles.
//
// ASMI = 0 (the default, every simulation): the four lines end at this
// block's ports, where a simulator's flash model connects - it watches
// flash_dclk, flash_ncs and flash_mosi and drives model_miso
// (tb/tbutil.EpcsPins with torqueloop/sim/epcs.py, the EPCS command set).
// With no model attached model_miso stays high, as an erased flash reads:
// the firmware finds nothing stored and SAVE answers STORE.
`default_nettype none

module tl_config_flash #(
    parameter integer ASMI = 0          // 1: through the Cyclone V's ASMI block; 0: a simulator's model
) (
    /* verilator lint_off UNUSEDSIGNAL */  // unused with ASMI = 0: the model reads them from outside
    input  wire flash_dclk,
    input  wire flash_ncs,             // active low
    input  wire flash_mosi,            // to the flash (its ASDI)
    /* verilator lint_on UNUSEDSIGNAL */
    output wire flash_miso             // from the flash (its DATA)
);

    // The simulator's flash model drives this (ASMI = 0); nothing in the design writes it.
    /* verilator lint_off UNUSEDSIGNAL */
    reg model_miso = 1'b1;
    /* verilator lint_on UNUSEDSIGNAL */

    generate
        if (ASMI != 0) begin : g_asmi
            /* verilator lint_off UNUSEDSIGNAL */
            wire [3:0] as_in;            // data0in, data2in, data3in: lines this design drives itself
            /* verilator lint_on UNUSEDSIGNAL */
            cyclonev_asmiblock #(.enable_sim("false")) u_asmi (
                .dclk(flash_dclk),
                .sce(flash_ncs),
                .oe(1'b0),
                .data0out(flash_mosi),
                .data1out(1'b0),
                .data2out(1'b1),
                .data3out(1'b1),
                .data0oe(1'b1),
                .data1oe(1'b0),
                .data2oe(1'b1),
                .data3oe(1'b1),
                .data0in(as_in[0]),
                .data1in(as_in[1]),
                .data2in(as_in[2]),
                .data3in(as_in[3])
            );
            assign flash_miso = as_in[1];
        end else begin : g_model
            assign flash_miso = model_miso;
        end
    endgenerate

endmodule

`default_nettype wire
