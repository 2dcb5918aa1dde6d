// SPDX-License-Identifier: MIT
// cyclonev_asmiblock: the INTERFACE of Intel's Cyclone V ASMI block, a
// primitive that exists only inside Quartus - written from its documented
// ports (Intel, AN 720 "Simulating the ASMI Block in Your Design", "Signals
// for ASMI Block" / "WYSIWYG for ASMI Block"), with no behaviour.
//
// It is here so that Verilator, slang and Yosys can read the board top as
// Quartus builds it (rtl/board/tl_config_flash.v with ASMI = 1): a black box
// for the linters and the constraint checks.  It is never part of a Quartus
// project (the real primitive is) nor of a simulation (there the flash is
// torqueloop/sim/epcs.py behind tl_config_flash's ports, ASMI = 0);
// torqueloop/flow/constraints_check.py checks both.
`default_nettype none

(* blackbox *)
module cyclonev_asmiblock #(
    /* verilator lint_off UNUSEDPARAM */
    parameter enable_sim = "false"      // "false": the real block (AN 720)
    /* verilator lint_on UNUSEDPARAM */
) (
    /* verilator lint_off UNUSEDSIGNAL */
    input  wire dclk,       // to the DCLK pin
    input  wire sce,        // to the nCSO pin
    input  wire oe,         // active low: DCLK and nCSO reach the flash
    input  wire data0out,   // to AS_DATA0 .. AS_DATA3 while their oe is 1
    input  wire data1out,
    input  wire data2out,
    input  wire data3out,
    input  wire data0oe,
    input  wire data1oe,
    input  wire data2oe,
    input  wire data3oe,
    /* verilator lint_on UNUSEDSIGNAL */
    /* verilator lint_off UNDRIVEN */
    output wire data0in,    // from AS_DATA0 .. AS_DATA3
    output wire data1in,
    output wire data2in,
    output wire data3in
    /* verilator lint_on UNDRIVEN */
);
endmodule

`default_nettype wire
