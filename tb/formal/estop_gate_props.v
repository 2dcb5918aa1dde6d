// SPDX-License-Identifier: MIT
// Safety properties of tl_estop_gate, proven by Yosys SAT (make lint), for
// every input - combinational, so they hold with no clock edge at all:
//  - KEY[0] pressed (key_n = 0): every bridge pin is low;
//  - a bridge pin is high only if its registered input is high and KEY[0]
//    is released: the gate can only remove drive, never add it.
`default_nettype none

module estop_gate_props #(
    parameter integer N = 8
) (
    input wire         key_n,
    input wire [N-1:0] drive_in
);
    wire [N-1:0] drive_out;

    tl_estop_gate #(.N(N)) dut (.key_n(key_n), .drive_in(drive_in), .drive_out(drive_out));

    always @(*) begin
        if (!key_n)
            assert (drive_out == {N{1'b0}});
        assert ((drive_out & ~drive_in) == {N{1'b0}});
        assert (drive_out == {N{1'b0}} || key_n);
    end
endmodule

`default_nettype wire
