// SPDX-License-Identifier: MIT
`default_nettype none
// M extension: MUL/MULH/MULHSU/MULHU in 3 cycles, DIV/DIVU/REM/REMU in 34
// (counted from `start` to `done`), or with RADIX4 in 15 or 18.
//
// Multiply: operands are registered at `start` as 33-bit signed numbers
// (sign or zero extended per instruction), each split into a signed high
// part h (17 bits) and an unsigned low part l (16 bits):
//   a*b = ah*bh*2^32 + (ah*bl + al*bh)*2^16 + al*bl
// MUL1: the four 17x17 products (one DSP block each) and the middle sum.
// MUL2: the low and high result words, the high one carry-selected on the
//       carry out of the low one, so that no stage holds more than one
//       ~35-bit carry chain (one 66-bit product in one cycle made the
//       longest path of the core; see docs/cpu.md).
//
// Divide: radix-2 restoring division of the magnitudes, one quotient bit per
// cycle (a 33-bit subtractor, no DSP), then the signs are applied.  The
// RISC-V corner cases fall out of this without special paths except one:
// x/0 gives an all-ones quotient and remainder x from the unsigned
// algorithm, and the quotient's sign correction is skipped for a zero
// divisor so that DIV x,0 = -1 as the spec requires; -2^31 / -1 gives
// quotient 2^31 (= -2^31) and remainder 0 naturally.
//
// RADIX4 (tl_cpu_pipe): two restoring steps per cycle, the second on the
// first's partial remainder (two 33-bit subtractors in series), so a divide
// takes 16 cycles of steps instead of 32.  In its first cycle the dividend's
// 8 leading quotient bits are skipped instead when they are known to be zero,
// its top byte (as a magnitude) below the divisor (a compare of registered
// values beside the steps).  Cycles from `start` to `done`: 1 + 16 + 1 = 18,
// or 1 + 1 + 12 + 1 = 15 with the skip; the control loop's divides (a 32-bit
// numerator over at least 8 bits of clock time) take 15.  Division by zero
// and -2^31 / -1 come out of the two steps as out of radix 2's one.
module tl_cpu_muldiv #(
    parameter RADIX4 = 0
) (
    input  wire        clk,
    input  wire        rst,
    input  wire        start,      // one-cycle pulse with funct3 and operands valid
    input  wire        abort,      // drop the operation in progress (interrupt)
    input  wire [2:0]  funct3,
    input  wire [31:0] a,          // rs1
    input  wire [31:0] b,          // rs2
    output wire        busy,
    output reg         done,       // one-cycle pulse, result valid
    output reg  [31:0] result,
    // A multiply's result one cycle before `done`, from MUL2's adders (a
    // core that can take it then saves a cycle; tl_cpu_pipe does)
    output wire        mul_last,   // MUL2: mul_word is the result
    output wire [31:0] mul_word
);
    localparam [2:0] IDLE = 3'd0, MUL1 = 3'd1, MUL2 = 3'd2, DIV = 3'd3, FIN = 3'd4;
    reg [2:0]  state;
    reg [1:0]  op;             // funct3[1:0]: which half / quotient or remainder
    reg [32:0] ma, mb;             // sign/zero-extended multiply operands
    // MUL1: partial products (bits above 31 of p_hh and above 34 of the
    // middle sum only weigh 2^64 and more)
    /* verilator lint_off UNUSEDSIGNAL */
    wire [31:0] pp_ll = ma[15:0] * mb[15:0];
    wire signed [33:0] pp_lh = $signed({1'b0, ma[15:0]}) * $signed(mb[32:16]);
    wire signed [33:0] pp_hl = $signed(ma[32:16]) * $signed({1'b0, mb[15:0]});
    wire signed [33:0] pp_hh = $signed(ma[32:16]) * $signed(mb[32:16]);
    /* verilator lint_on UNUSEDSIGNAL */
    reg  [31:0] p_ll, p_hh;
    reg  [34:0] p_mid;
    // MUL2: low word = p_ll + p_mid * 2^16; high word = p_hh + p_mid / 2^16 + carry
    wire [16:0] lo_hi16 = {1'b0, p_ll[31:16]} + {1'b0, p_mid[15:0]};
    wire [31:0] mid_hi  = {{13{p_mid[34]}}, p_mid[34:16]};
    wire [31:0] hi_c0   = p_hh + mid_hi;
    wire [31:0] hi_c1   = p_hh + mid_hi + 32'd1;
    assign mul_word = op == 2'b00 ? {lo_hi16[15:0], p_ll[15:0]} : (lo_hi16[16] ? hi_c1 : hi_c0);
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
    // RADIX4: a second step on the first one's partial remainder
    wire [31:0] rem1      = trial[32] ? rem_shift[31:0] : trial[31:0];
    wire [32:0] rem_shift2 = {rem1, quo[30]};
    wire [32:0] trial2    = rem_shift2 - {1'b0, divisor};
    wire        first     = count == 6'd16;              // RADIX4's first cycle of steps
    wire        skip8     = {24'd0, quo[31:24]} < divisor; // quotient bits 31..24 all zero

    assign busy = state != IDLE;
    assign mul_last = state == MUL2;

    always @(posedge clk) begin
        done <= 1'b0;
        if (rst || abort) begin
            state <= IDLE;
        end else begin
            case (state)
                IDLE: if (start) begin
                    op <= funct3[1:0];
                    if (!funct3[2]) begin
                        ma <= {a_neg, a};
                        mb <= {b_neg, b};
                        state <= MUL1;
                    end else begin
                        quo     <= a_neg ? 32'd0 - a : a;   // dividend magnitude, shifted out MSB first
                        divisor <= b_neg ? 32'd0 - b : b;
                        rem     <= 32'd0;
                        count   <= RADIX4 ? 6'd16 : 6'd32;
                        neg_q   <= (a_neg ^ b_neg) && b != 32'd0;
                        neg_r   <= a_neg;
                        state   <= DIV;
                    end
                end
                MUL1: begin
                    p_ll  <= pp_ll;
                    p_hh  <= pp_hh[31:0];
                    p_mid <= {pp_lh[33], pp_lh} + {pp_hl[33], pp_hl};
                    state <= MUL2;
                end
                MUL2: begin
                    result <= mul_word;
                    done  <= 1'b1;
                    state <= IDLE;
                end
                DIV: begin
                    count <= count - 6'd1;
                    if (RADIX4 != 0 && first && skip8) begin   // 8 zero quotient bits at once
                        rem   <= {24'd0, quo[31:24]};
                        quo   <= {quo[23:0], 8'd0};
                        count <= 6'd12;
                    end else if (RADIX4 != 0) begin
                        rem <= trial2[32] ? rem_shift2[31:0] : trial2[31:0];
                        quo <= {quo[29:0], !trial[32], !trial2[32]};
                    end else if (!trial[32]) begin
                        rem <= trial[31:0];
                        quo <= {quo[30:0], 1'b1};
                    end else begin
                        rem <= rem_shift[31:0];
                        quo <= {quo[30:0], 1'b0};
                    end
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
