// SPDX-License-Identifier: MIT
`default_nettype none
// M extension: MUL/MULH/MULHSU/MULHU in 3 cycles, DIV/DIVU/REM/REMU in 34
// (counted from `start` to `done`), or with RADIX4 in 11, 15 or 19.
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
// RADIX4 (tl_cpu_pipe): two quotient bits per cycle, the partial remainder
// compared with d, 2d and 3d at once (three subtractors side by side, 3d
// registered in a first cycle, DIV3), so a cycle's path is one subtractor and
// a 4-way select, as long as radix 2's one subtractor and 2-way select.  In
// the DIV3 cycle the dividend's leading quotient bits are skipped when they
// are known to be zero: 16 of them when its high half is below the divisor, 8
// when its top byte is (both compares of registered values, beside the 3d
// adder).  Cycles from `start` to `done`: 1 + 1 + (32 - skip) / 2 + 1, so 19,
// 15 or 11; the control loop's divides (a 32-bit numerator over at least 8
// bits of clock time) take 15.  Division by zero: the partial remainder is
// never below 3d = 0, so every quotient bit is 1 and the remainder is the
// dividend, as in radix 2.
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
    localparam [2:0] IDLE = 3'd0, MUL1 = 3'd1, MUL2 = 3'd2, DIV = 3'd3, FIN = 3'd4, DIV3 = 3'd5;
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
    // RADIX4: the next two dividend bits in; rem < divisor, so rs4 < 4 divisor
    reg  [33:0] div3;                                   // 3 divisor (< 2^34)
    wire [33:0] rs4 = {rem, quo[31:30]};
    // (a difference that is not negative is below the divisor: its bits 33..32 are zero)
    /* verilator lint_off UNUSEDSIGNAL */
    wire [34:0] t1  = {1'b0, rs4} - {3'b000, divisor};
    wire [34:0] t2  = {1'b0, rs4} - {2'b00, divisor, 1'b0};
    wire [34:0] t3  = {1'b0, rs4} - {1'b0, div3};
    /* verilator lint_on UNUSEDSIGNAL */
    wire        skip16 = {16'd0, quo[31:16]} < divisor; // quotient bits 31..16 all zero
    wire        skip8  = {24'd0, quo[31:24]} < divisor; // quotient bits 31..24 all zero

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
                        state   <= RADIX4 ? DIV3 : DIV;
                    end
                end
                DIV3: begin   // RADIX4 only: 3 divisor, and the leading zero quotient bits skipped
                    div3 <= {2'b00, divisor} + {1'b0, divisor, 1'b0};
                    if (skip16) begin
                        rem   <= {16'd0, quo[31:16]};
                        quo   <= {quo[15:0], 16'd0};
                        count <= 6'd8;
                    end else if (skip8) begin
                        rem   <= {24'd0, quo[31:24]};
                        quo   <= {quo[23:0], 8'd0};
                        count <= 6'd12;
                    end
                    state <= DIV;
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
                    if (RADIX4 != 0) begin
                        if (!t3[34]) begin
                            rem <= t3[31:0];
                            quo <= {quo[29:0], 2'b11};
                        end else if (!t2[34]) begin
                            rem <= t2[31:0];
                            quo <= {quo[29:0], 2'b10};
                        end else if (!t1[34]) begin
                            rem <= t1[31:0];
                            quo <= {quo[29:0], 2'b01};
                        end else begin
                            rem <= rs4[31:0];
                            quo <= {quo[29:0], 2'b00};
                        end
                    end else if (!trial[32]) begin
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
