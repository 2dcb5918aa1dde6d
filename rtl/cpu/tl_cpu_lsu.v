// SPDX-License-Identifier: MIT
`default_nettype none
// Load/store unit: data-bus byte lanes for a store, alignment check, and
// the extraction and sign/zero extension of loaded bytes.  Combinational.
// The data bus is 32 bits wide and word-addressed by the slave; dbus_addr
// keeps the byte address and dbus_be names the bytes used (for loads too,
// so a peripheral may tell a byte read from a word read).
module tl_cpu_lsu (
    input  wire [2:0]  funct3,      // LB LH LW LBU LHU / SB SH SW
    input  wire [1:0]  off,         // effective byte address, low bits
    input  wire [31:0] store_data,  // rs2
    output wire        misaligned,
    output reg  [3:0]  be,
    output reg  [31:0] wdata,
    input  wire [31:0] rdata,       // the addressed bus word
    output reg  [31:0] load_data    // extended for rd
);
    assign misaligned = (funct3[1:0] == 2'b01 && off[0]) ||
                        (funct3[1:0] == 2'b10 && off != 2'b00);

    always @(*) begin
        case (funct3[1:0])
            2'b00: begin
                be    = 4'b0001 << off;
                wdata = {4{store_data[7:0]}};
            end
            2'b01: begin
                be    = off[1] ? 4'b1100 : 4'b0011;
                wdata = {2{store_data[15:0]}};
            end
            default: begin
                be    = 4'b1111;
                wdata = store_data;
            end
        endcase
    end

    wire [15:0] shifted = rdata[{off[1], 4'b0000} +: 16] >> {off[0], 3'b000};
    always @(*) begin
        case (funct3)
            3'b000:  load_data = {{24{shifted[7]}}, shifted[7:0]};
            3'b001:  load_data = {{16{shifted[15]}}, shifted[15:0]};
            3'b100:  load_data = {24'd0, shifted[7:0]};
            3'b101:  load_data = {16'd0, shifted[15:0]};
            default: load_data = rdata;
        endcase
    end
endmodule
`default_nettype wire
