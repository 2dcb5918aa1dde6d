// SPDX-License-Identifier: MIT
`default_nettype none
// Instruction decoder: register numbers, immediate and instruction class of
// one 32-bit RV32IM/Zicsr instruction word.  Purely combinational.
// Every encoding not listed in the RV32I, M and Zicsr chapters (and mret/wfi
// of the privileged spec) raises `illegal`, which the core turns into a
// precise illegal-instruction exception.
module tl_cpu_decode (
    input  wire [31:0] insn,
    output wire [4:0]  rd,
    output wire [4:0]  rs1,
    output wire [2:0]  funct3,
    output reg  [31:0] imm,
    // the instruction class, bit 0 first: is_lui, is_auipc, is_jal, is_jalr,
    // is_branch, is_load, is_store, alu_use_imm (OP-IMM: operand b is the
    // immediate), alu_alt (SUB / SRA / SRAI), is_muldiv, is_csr, csr_writes
    // (CSRRW(I) always, CSRRS/C(I) only with rs1/zimm != 0), is_ecall,
    // is_ebreak, is_mret, writes_rd, illegal
    output wire [16:0] flags
);
    wire is_lui, is_auipc, is_jal, is_jalr, is_branch, is_load, is_store, alu_use_imm, alu_alt;
    wire is_muldiv, is_csr, csr_writes, is_ecall, is_ebreak, is_mret, writes_rd, illegal;
    assign flags = {illegal, writes_rd, is_mret, is_ebreak, is_ecall, csr_writes, is_csr, is_muldiv,
                    alu_alt, alu_use_imm, is_store, is_load, is_branch, is_jalr, is_jal, is_auipc, is_lui};

    wire [6:0] opcode = insn[6:0];
    wire [6:0] funct7 = insn[31:25];
    assign rd     = insn[11:7];
    assign rs1    = insn[19:15];
    assign funct3 = insn[14:12];

    wire op_lui    = opcode == 7'b0110111;
    wire op_auipc  = opcode == 7'b0010111;
    wire op_jal    = opcode == 7'b1101111;
    wire op_jalr   = opcode == 7'b1100111;
    wire op_branch = opcode == 7'b1100011;
    wire op_load   = opcode == 7'b0000011;
    wire op_store  = opcode == 7'b0100011;
    wire op_imm    = opcode == 7'b0010011;
    wire op_reg    = opcode == 7'b0110011;
    wire op_fence  = opcode == 7'b0001111;
    wire op_system = opcode == 7'b1110011;

    // Legal sub-encodings per opcode
    wire jalr_ok   = funct3 == 3'b000;
    wire branch_ok = funct3 != 3'b010 && funct3 != 3'b011;
    wire load_ok   = funct3 != 3'b011 && funct3 != 3'b110 && funct3 != 3'b111;
    wire store_ok  = funct3[2] == 1'b0 && funct3 != 3'b011;
    wire imm_ok    = (funct3 == 3'b001) ? (funct7 == 7'b0000000) :
                     (funct3 == 3'b101) ? (funct7 == 7'b0000000 || funct7 == 7'b0100000) : 1'b1;
    wire reg_base  = funct7 == 7'b0000000 ||
                     (funct7 == 7'b0100000 && (funct3 == 3'b000 || funct3 == 3'b101));
    wire reg_m     = funct7 == 7'b0000001;
    wire fence_ok  = funct3 == 3'b000 || funct3 == 3'b001;

    wire sys_priv  = op_system && funct3 == 3'b000;
    assign is_ecall  = sys_priv && insn == 32'h0000_0073;
    assign is_ebreak = sys_priv && insn == 32'h0010_0073;
    assign is_mret   = sys_priv && insn == 32'h3020_0073;
    wire   is_wfi    = sys_priv && insn == 32'h1050_0073;
    assign is_csr    = op_system && funct3 != 3'b000 && funct3 != 3'b100;
    assign csr_writes = funct3[1:0] == 2'b01 || rs1 != 5'd0;

    assign is_lui      = op_lui;
    assign is_auipc    = op_auipc;
    assign is_jal      = op_jal;
    assign is_jalr     = op_jalr && jalr_ok;
    assign is_branch   = op_branch && branch_ok;
    assign is_load     = op_load && load_ok;
    assign is_store    = op_store && store_ok;
    // OP-IMM or OP without M: the ALU result is written back
    wire   is_alu      = (op_imm && imm_ok) || (op_reg && reg_base);
    assign alu_use_imm = op_imm;
    // bit 30 selects SUB/SRA; for OP-IMM only the shift-right form has it (ADDI has no SUBI)
    assign alu_alt     = insn[30] && (op_reg || funct3 == 3'b101);
    assign is_muldiv   = op_reg && reg_m;
    // FENCE, FENCE.I, WFI: no architectural effect on this core (no caches, no sleep)
    wire   is_nop      = (op_fence && fence_ok) || is_wfi;

    assign writes_rd = is_lui || is_auipc || is_jal || is_jalr || is_load || is_alu ||
                       is_muldiv || is_csr;
    assign illegal = !(writes_rd || is_branch || is_store || is_ecall || is_ebreak ||
                       is_mret || is_nop);

    // Immediates by instruction format (RV32I base, chapter 2.3)
    always @(*) begin
        if (op_store)
            imm = {{20{insn[31]}}, insn[31:25], insn[11:7]};
        else if (op_branch)
            imm = {{19{insn[31]}}, insn[31], insn[7], insn[30:25], insn[11:8], 1'b0};
        else if (op_lui || op_auipc)
            imm = {insn[31:12], 12'd0};
        else if (op_jal)
            imm = {{11{insn[31]}}, insn[31], insn[19:12], insn[20], insn[30:21], 1'b0};
        else
            imm = {{20{insn[31]}}, insn[31:20]};
    end
endmodule
`default_nettype wire
