`default_nettype none
// M extension: MUL/MULH/MULHSU/MULHU in 2 cycles, DIV/DIVU/REM/REMU in 34
// (counted from `start` to `done`).
//
// Multiply: operands are registered at `start` and the selected half of the
// 33x33 signed product is registered one cycle later, when `done` pulses
// (DSP blocks between registers, so neither the register file nor the
// write-back mux sits in the multiplier path).
//
// Divide: radix-2 restoring division of the magnitudes, one quotient bit per
// cycle (a 33-bit subtractor, no DSP), then the signs are applied.  The
// RISC-V corner cases fall out of this without special paths except one:
// x/0 gives an all-ones quotient and remainder x from the unsigned
// algorithm, and the quotient's sign correction is skipped for a zero
// divisor so that DIV x,0 = -1 as the spec requires; -2^31 / -1 gives
// quotient 2^31 (= -2^31) and remainder 0 naturally.
module cpu_muldiv (
    input  wire        clk,
    input  wire        rst,
    input  wire        start,      // one-cycle pulse with funct3 and operands valid
    input  wire [2:0]  funct3,
    input  wire [31:0] a,          // rs1
    input  wire [31:0] b,          // rs2
    output wire        busy,
    output reg         done,       // one-cycle pulse, result valid
    output reg  [31:0] result
);
    localparam [1:0] IDLE = 2'd0, MUL = 2'd1, DIV = 2'd2, FIN = 2'd3;
    reg [1:0]  state;
    reg [1:0]  op;             // funct3[1:0]: which half / quotient or remainder
    reg [32:0] ma, mb;             // sign/zero-extended multiply operands
    // 66-bit signed product of which bits 63:0 are the 32x32 result; 65:64
    // are only the sign extension.
    /* verilator lint_off UNUSEDSIGNAL */
    wire [65:0] product = $signed(ma) * $signed(mb);
    /* verilator lint_on UNUSEDSIGNAL */
    reg [31:0] quo, rem, divisor;
    reg [5:0]  count;
    reg        neg_q, neg_r;

    wire a_signed = funct3[1:0] != 2'b11 && !(funct3[2] && funct3[0]);  // MULH, MULHSU(a), DIV, REM
    wire b_signed = funct3[1:0] == 2'b00 || funct3[1:0] == 2'b01;       // MUL, MULH, DIV, REM
    wire a_neg    = funct3[2] ? (!funct3[0] && a[31]) : (a_signed && a[31]);
    wire b_neg    = funct3[2] ? (!funct3[0] && b[31]) : (b_signed && b[31]);

    // One restoring step: shift the next dividend bit into the partial remainder.
    wire [32:0] rem_shift = {rem, quo[31]};
    wire [32:0] trial     = rem_shift - {1'b0, divisor};

    assign busy = state != IDLE;

    always @(posedge clk) begin
        done <= 1'b0;
        if (rst) begin
            state <= IDLE;
        end else begin
            case (state)
                IDLE: if (start) begin
                    op <= funct3[1:0];
                    if (!funct3[2]) begin
                        ma <= {a_neg, a};
                        mb <= {b_neg, b};
                        state <= MUL;
                    end else begin
                        quo     <= a_neg ? 32'd0 - a : a;   // dividend magnitude, shifted out MSB first
                        divisor <= b_neg ? 32'd0 - b : b;
                        rem     <= 32'd0;
                        count   <= 6'd32;
                        neg_q   <= (a_neg ^ b_neg) && b != 32'd0;
                        neg_r   <= a_neg;
                        state   <= DIV;
                    end
                end
                MUL: begin
                    result <= (op[1:0] == 2'b00) ? product[31:0] : product[63:32];
                    done   <= 1'b1;
                    state  <= IDLE;
                end
                DIV: begin
                    if (!trial[32]) begin
                        rem <= trial[31:0];
                        quo <= {quo[30:0], 1'b1};
                    end else begin
                        rem <= rem_shift[31:0];
                        quo <= {quo[30:0], 1'b0};
                    end
                    count <= count - 6'd1;
                    if (count == 6'd1)
                        state <= FIN;
                end
                default: begin  // FIN: apply the signs
                    if (op[1])
                        result <= neg_r ? 32'd0 - rem : rem;
                    else
                        result <= neg_q ? 32'd0 - quo : quo;
                    done  <= 1'b1;
                    state <= IDLE;
                end
            endcase
        end
    end
endmodule
`default_nettype wire
