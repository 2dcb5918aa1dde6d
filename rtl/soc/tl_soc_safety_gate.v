// SPDX-License-Identifier: MIT
// tl_soc_safety_gate: the last stage before the bridge pins.  It forces every
// PWM pin low while the SoC is in reset, while soc_sys says `safe`, or while
// the raw e-stop pin is high - the last one combinationally, without a
// clock, so a pressed e-stop cuts the drive even before its synchroniser
// has seen it and even with the clock stopped.  With both PWM inputs low a
// BTS7960 bridge sources no energy from the supply (brake or coast only), so
// no firmware state can make an axis move.  The enables pass through: the
// PWM block chooses brake or coast for its safe state.  Proven by
// tb/formal/soc_safety_props.v.  Purely combinational; every input is either
// a register output or the asynchronous e-stop pin, whose glitches can only
// switch the drive off.
`default_nettype none

module tl_soc_safety_gate #(
    parameter integer N_AXES = 2
) (
    input  wire              rst,
    input  wire              safe,
    input  wire              estop_pin,   // asynchronous, 1 = stop
    input  wire [N_AXES-1:0] rpwm_in,
    input  wire [N_AXES-1:0] lpwm_in,
    input  wire [N_AXES-1:0] pwm_in,      // PWM+DIR mode PWM pin
    output wire [N_AXES-1:0] rpwm,
    output wire [N_AXES-1:0] lpwm,
    output wire [N_AXES-1:0] pwm
);

    wire off = rst | safe | estop_pin;

    assign rpwm = rpwm_in & {N_AXES{~off}};
    assign lpwm = lpwm_in & {N_AXES{~off}};
    assign pwm  = pwm_in  & {N_AXES{~off}};

endmodule

`default_nettype wire
