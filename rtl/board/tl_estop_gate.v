// SPDX-License-Identifier: MIT
// tl_estop_gate: the bridge pins' very last stage - the emergency stop without a clock.
//
// tl_drive_interlock's outputs are registered (its gating logic must not
// glitch onto the pins), so by themselves they need CLOCK_50 to drop after
// KEY[0]: a stopped or failed clock would leave a driving bridge driving.
// Here every bridge input (RPWM, LPWM, R_EN, L_EN of every axis) is ANDed
// with the raw KEY[0] level (1 = released): pressing the key forces all of
// them low through one gate, with no clock and no synchroniser.
//
// Glitch-free: each output is one 2-input AND of a flip-flop output and the
// KEY[0] pin (tests/test_estop_gate.py checks the synthesised netlist has
// exactly that shape).  A change of KEY[0] alone can only take an output
// low or back to the flip-flop's value - with the flip-flop low it cannot
// produce a high pulse - and a change of the flip-flop is the registered,
// glitch-free edge the interlock already made.  Bounce of the key while
// pressed can therefore only chop a driving output, never drive an idle
// one; the interlock disarms within 4 clocks of the press anyway.
// Proven in make lint (tb/formal/estop_gate_props.v): key pressed -> every
// output low; an output high -> its input high and the key released.
`default_nettype none

module tl_estop_gate #(
    parameter integer N = 8
) (
    input  wire         key_n,   // raw KEY[0] pin, 1 = released (asynchronous)
    input  wire [N-1:0] drive_in,    // registered bridge inputs from tl_drive_interlock
    output wire [N-1:0] drive_out    // to the header pins
);

    assign drive_out = drive_in & {N{key_n}};

endmodule

`default_nettype wire
