// SPDX-License-Identifier: MIT
`default_nettype none
// Integer ALU of RV32I (OP and OP-IMM) and the branch comparator.
// The comparator is separate from the adder so that branches resolve in the
// same execute cycle that the ALU computes a result.
module tl_cpu_alu (
    input  wire [2:0]  funct3,
    input  wire        alt,        // SUB / SRA
    input  wire [31:0] a,
    input  wire [31:0] b,
    output reg  [31:0] result,
    // branch condition on rs1/rs2 with the branch funct3
    input  wire [31:0] cmp_a,
    input  wire [31:0] cmp_b,
    output reg         branch_taken
);
    wire        lt_s = $signed(a) < $signed(b);
    wire        lt_u = a < b;
    wire [4:0]  shamt = b[4:0];

    always @(*) begin
        case (funct3)
            3'b000: result = alt ? a - b : a + b;
            3'b001: result = a << shamt;
            3'b010: result = {31'd0, lt_s};
            3'b011: result = {31'd0, lt_u};
            3'b100: result = a ^ b;
            3'b101: result = alt ? $unsigned($signed(a) >>> shamt) : a >> shamt;
            3'b110: result = a | b;
            default: result = a & b;
        endcase
    end

    wire eq     = cmp_a == cmp_b;
    wire cmp_lt = $signed(cmp_a) < $signed(cmp_b);
    wire cmp_lu = cmp_a < cmp_b;
    always @(*) begin
        case (funct3)
            3'b000:  branch_taken = eq;
            3'b001:  branch_taken = !eq;
            3'b100:  branch_taken = cmp_lt;
            3'b101:  branch_taken = !cmp_lt;
            3'b110:  branch_taken = cmp_lu;
            3'b111:  branch_taken = !cmp_lu;
            default: branch_taken = 1'b0;
        endcase
    end
endmodule
`default_nettype wire
