// SPDX-License-Identifier: MIT
`default_nettype none
`include "tl_cpu_bus.vh"
// torqueloop CPU: RV32IM + Zicsr, machine mode only, multi-cycle with the
// next instruction fetch overlapped with the completing cycle.
//
// Port contract (shared with the SoC in rtl/soc): instruction and data bus
// with the same handshake.  The master holds *_req and the request fields
// stable until the slave pulses *_ack for one cycle; *_rdata and *_err are
// valid with *_ack.  A slave acks at the earliest in the cycle after it
// first sees *_req and must not start a new transfer in its ack cycle
// (the CPU may keep *_req high through the ack cycle and into the next
// request).  Any number of wait states works.  Reset is synchronous, active
// high; interrupt lines are levels synchronous to clk.
//
// Control (see docs/cpu.md for the cycle counts):
//   FETCH  : hold the instruction request (address pc) until ack.
//   EXEC   : decode the instruction register, read rs1/rs2, ALU / branch /
//            CSR / trap decision.  Single-cycle instructions complete here
//            and request the next instruction in the same cycle - except
//            conditional branches and jalr, whose target depends on the
//            register values (the comparator, rs1 + imm): they complete
//            here and their fetch starts in the next cycle from the
//            registered pc, so no register-file-to-fetch-address path
//            limits the clock (docs/cpu.md, timing).
//            Loads and stores raise dbus_req in this cycle already; loads,
//            stores, multiplies and divides also prefetch pc+4 here.
//   MEM    : wait for dbus_ack and the prefetch (load write-back, or access fault).
//   MULDIV : wait for the multiply/divide unit and the prefetch.
// With a zero-wait-state bus (ack in the cycle after the request) that is
// 2 cycles per ALU/jal/CSR instruction, word load and store, 3 per
// conditional branch, jalr and byte/halfword load, 4 per multiply and 35
// per divide.  The handshake itself sets the floor of 2:
// a slave cannot accept a new request in its ack cycle.
// Interrupts are taken in EXEC before the instruction executes (mepc = its
// pc), or during a multiply/divide, which is then abandoned and re-executed
// after mret; loads and stores always complete.
//
// Parameters and ports: `CPU_CORE_PARAMS and `CPU_CORE_PORTS of tl_cpu_bus.vh.
module tl_cpu #(`CPU_CORE_PARAMS) (`CPU_CORE_PORTS);
`include "tl_cpu_causes.vh"
    localparam [1:0] S_FETCH = 2'd0, S_EXEC = 2'd1, S_MEM = 2'd2, S_MULDIV = 2'd3;
    reg [1:0]  state;
    reg [31:0] pc;

    wire in_fetch = state == S_FETCH;
    wire in_exec  = state == S_EXEC;
    wire in_mem   = state == S_MEM;
    wire in_md    = state == S_MULDIV;

    // ---- fetch -------------------------------------------------------------
    wire        complete, to_exec, fetch_start, prefetch;
    reg  [31:0] next_pc;
    wire [31:0] next_pc_seq;      // next_pc without a taken branch's or jalr's target (below)
    wire [31:0] insn, insn_next, pc_plus4;
    wire [4:0]  next_rs1, next_rs2;
    wire        insn_load;
    wire        fetched, fetch_fault, fetch_pending, pf_done, pf_bad;
    tl_cpu_fetch u_fetch (
        .clk(clk), .rst(rst), .start(fetch_start),
        .start_addr(prefetch ? pc_plus4 : (complete ? next_pc_seq : pc)),
        .waiting(in_fetch), .prefetching(in_mem || in_md), .take_prefetch(to_exec),
        .ibus_req(ibus_req), .ibus_addr(ibus_addr), .ibus_ack(ibus_ack),
        .ibus_rdata(ibus_rdata), .ibus_err(ibus_err), .pending(fetch_pending),
        .insn(insn), .insn_next(insn_next), .insn_load(insn_load), .next_rs1(next_rs1), .next_rs2(next_rs2), .fetched(fetched), .fault(fetch_fault), .pf_done(pf_done), .pf_bad(pf_bad)
    );

    // ---- decode and register file --------------------------------------------
    // The word is decoded as it enters the instruction register (fetch's
    // insn_next) and the decode is registered beside it, so EXEC starts from
    // flip-flops rather than from a decoder behind the instruction register
    // (the core's longest path ran through the immediate decode: docs/cpu.md, Timing).
    wire [4:0]  rd, rs1;
    wire [2:0]  funct3;
    wire [31:0] imm;
    wire is_lui, is_auipc, is_jal, is_jalr, is_branch, is_load, is_store;
    wire alu_use_imm, alu_alt, is_muldiv, is_csr, csr_writes, is_ecall, is_ebreak;
    wire is_mret, writes_rd, dec_illegal;
    wire [4:0]  rd_d, rs1_d;
    wire [2:0]  funct3_d;
    wire [31:0] imm_d;
    wire [16:0] flags_d;
    tl_cpu_decode u_decode (
        .insn(insn_next), .rd(rd_d), .rs1(rs1_d), .funct3(funct3_d), .imm(imm_d), .flags(flags_d)
    );
    reg [61:0] dec_q;            // {flags, imm, funct3, rs1, rd} of the word in insn
    always @(posedge clk) begin
        if (insn_load)
            dec_q <= {flags_d, imm_d, funct3_d, rs1_d, rd_d};
    end
    assign {rd, rs1, funct3, imm} = {dec_q[4:0], dec_q[9:5], dec_q[12:10], dec_q[44:13]};
    assign {writes_rd, is_mret, is_ebreak, is_ecall, csr_writes, is_csr, is_muldiv, alu_alt,
            alu_use_imm, is_store, is_load, is_branch, is_jalr, is_jal, is_auipc, is_lui} = dec_q[60:45];
    assign dec_illegal = dec_q[61];

    wire        rf_we;
    reg  [31:0] rf_wdata;
    wire [31:0] rs1_val, rs2_val;
    // Read with the register numbers of the word entering the instruction
    // register, so rs1/rs2 are ready in EXEC (block RAM, registered read).
    /* verilator lint_off PINCONNECTEMPTY */
    tl_cpu_regfile u_regfile (
        .clk(clk), .we(rf_we), .waddr(rd), .wdata(rf_wdata),
        .re(insn_load), .raddr1(next_rs1), .raddr2(next_rs2),
        .rdata1(rs1_val), .rdata2(rs2_val), .word1(), .word2()
    );
    /* verilator lint_on PINCONNECTEMPTY */

    // ---- execute -------------------------------------------------------------
    wire [31:0] alu_result;
    wire        branch_taken;
    tl_cpu_alu u_alu (
        .funct3(funct3), .alt(alu_alt), .a(rs1_val), .b(alu_use_imm ? imm : rs2_val),
        .result(alu_result), .cmp_a(rs1_val), .cmp_b(rs2_val), .branch_taken(branch_taken)
    );

    assign      pc_plus4 = pc + 32'd4;
    wire [31:0] pc_imm   = pc + imm;          // JAL, branches, AUIPC
    wire [31:0] eff_addr = rs1_val + imm;     // loads, stores (S-imm), JALR
    // The branch comparator's result is the last signal of EXEC to settle,
    // and the next fetch address depends on it: it joins only at the end -
    // in the choice between the next pc of a taken branch and of anything
    // else, and in the taken branch's own misaligned-target trap - so that
    // nothing else (trap priority, completion, the data bus) waits for it.
    wire        jumps_always = is_jal || is_jalr;
    wire        br_taken     = in_exec && is_branch && branch_taken;
    wire [31:0] jump_target  = is_jalr ? {eff_addr[31:1], 1'b0} : pc_imm;
    // Without the C extension every target must be 4-byte aligned; bit 0 is
    // already zero for all three kinds of jump, pc[1:0] is zero, so a branch
    // target is misaligned exactly when its immediate's bit 1 is set.
    wire        jump_misaligned   = jumps_always && jump_target[1];
    wire        branch_misaligned = pc_imm[1];

    // ---- load/store ------------------------------------------------------------
    // The data access and the prefetch of pc+4 run in parallel; whichever
    // answers first is remembered until the other one has answered too.
    reg         d_done, d_err_q;
    reg  [31:0] d_rdata_q;
    // A word load (or a store) finishes in the ack cycle, the bus word going
    // straight to rd; a byte or halfword load finishes a cycle later, its
    // alignment and extension working on the registered word, so that no
    // block-RAM output runs through the byte shifter into the register file
    // in one clock (docs/cpu.md, timing).
    wire        load_sub = is_load && funct3[1:0] != 2'b10;
    wire        d_fin   = d_done || (dbus_ack && !load_sub);
    wire        d_error = d_done ? d_err_q : dbus_err;
    wire [31:0] d_rdata = d_done ? d_rdata_q : dbus_rdata;
    wire        mem_misaligned;
    wire [31:0] load_data;
    tl_cpu_lsu u_lsu (
        .funct3(funct3), .off(eff_addr[1:0]), .store_data(rs2_val),
        .misaligned(mem_misaligned), .be(dbus_be), .wdata(dbus_wdata),
        .rdata(d_rdata_q), .load_data(load_data)
    );

    // ---- CSRs and traps -----------------------------------------------------------
    wire [31:0] csr_rdata, trap_target, mepc;
    wire        csr_illegal, irq_pending;
    wire [3:0]  irq_code;
    // The multiply/divide unit's completion, used by the trap logic below
    // (Verilog wants a name declared before its first use).
    wire        md_done;
    reg         md_done_q;
    wire        md_fin;
    reg         trap_early, trap_irq;   // every trap but a taken branch's misaligned target
    reg  [3:0]  trap_code;
    reg  [31:0] trap_tval_early;

    wire ex_illegal = dec_illegal || (is_csr && csr_illegal);
    always @(*) begin
        trap_early = 1'b0;
        trap_irq   = 1'b0;
        trap_code  = 4'd0;
        trap_tval_early = 32'd0;
        case (state)
            S_FETCH: if (fetch_fault) begin
                trap_early = 1'b1; trap_code = CAUSE_FETCH_FAULT; trap_tval_early = pc;
            end
            S_EXEC: begin
                trap_early = 1'b1;
                if (irq_pending) begin
                    trap_irq = 1'b1; trap_code = irq_code;
                end else if (ex_illegal) begin
                    trap_code = CAUSE_ILLEGAL; trap_tval_early = insn;
                end else if (is_ecall) begin
                    trap_code = CAUSE_ECALL_M;
                end else if (is_ebreak) begin
                    trap_code = CAUSE_BREAKPOINT; trap_tval_early = pc;
                end else if (jump_misaligned) begin
                    trap_code  = CAUSE_FETCH_MISALIGNED; trap_tval_early = jump_target;
                end else if ((is_load || is_store) && mem_misaligned) begin
                    trap_code = is_store ? CAUSE_STORE_MISALIGNED : CAUSE_LOAD_MISALIGNED; trap_tval_early = eff_addr;
                end else begin
                    trap_early = 1'b0;
                end
            end
            S_MEM: if (d_fin && pf_done && d_error) begin
                trap_early = 1'b1; trap_code = is_store ? CAUSE_STORE_FAULT : CAUSE_LOAD_FAULT; trap_tval_early = eff_addr;
            end
            // An interrupt abandons a multiply/divide still in progress (it
            // is re-executed after mret: mepc = its pc, rd not written), so
            // the interrupt latency does not grow with the divider's 34
            // cycles.  The prefetch must have answered first.
            S_MULDIV: if (irq_pending && pf_done && !md_fin) begin
                trap_early = 1'b1; trap_irq = 1'b1; trap_code = irq_code;
            end
            default: ;
        endcase
    end

    // A taken branch to a misaligned target (instruction-address-misaligned,
    // cause 0, tval = the target) ranks after the traps above, none of which
    // a branch that reached it raises.
    wire        br_trap   = br_taken && branch_misaligned && !trap_early;
    wire        trap      = trap_early || br_trap;
    wire [31:0] trap_tval = br_trap ? pc_imm : trap_tval_early;

    // Loads, stores, multiplies, CSRs and mret are no branches: trap_early decides for them.
    wire exec_go  = in_exec && !trap_early;
    wire exec_mem = exec_go && (is_load || is_store);
    wire exec_md  = exec_go && is_muldiv;

    tl_cpu_csr #(.HART_ID(HART_ID)) u_csr (
        .clk(clk), .rst(rst),
        .addr(insn[31:20]), .op(funct3[1:0]),
        .src(funct3[2] ? {27'd0, rs1} : rs1_val),
        .writes(csr_writes), .commit(exec_go && is_csr),
        .rdata(csr_rdata), .illegal(csr_illegal),
        .trap(trap && !rst), .trap_irq(trap_irq), .trap_code(trap_code), .trap_pc(pc),
        .trap_tval(trap_tval), .trap_target(trap_target),
        .mret(exec_go && is_mret), .mepc_out(mepc),
        `CPU_IRQ_CONNECT, .irq_pending(irq_pending), .irq_code(irq_code), .retire(retire)
    );

    // ---- multiply / divide (md_done, md_done_q, md_fin declared above) ---------
    wire [31:0] md_result;
    /* verilator lint_off PINCONNECTEMPTY */
    tl_cpu_muldiv u_muldiv (
        .clk(clk), .rst(rst), .start(exec_md && !rst), .abort(in_md && trap_early), .funct3(funct3),
        .a(rs1_val), .b(rs2_val), .busy(), .done(md_done), .result(md_result), .mul_last(), .mul_word()
    );
    /* verilator lint_on PINCONNECTEMPTY */
    assign md_fin = md_done || md_done_q;

    // ---- completion, write-back, next pc --------------------------------------------
    assign prefetch = exec_mem || exec_md;
    // (a trapping branch completes as a non-trapping one would: no need for br_trap)
    assign complete = trap_early || (exec_go && !prefetch) ||
                      (in_mem && d_fin && pf_done) || (in_md && md_fin && pf_done);
    assign retire   = complete && !trap && !rst;
    assign rf_we    = retire && writes_rd;
    // After a load/store/muldiv the prefetched pc+4 goes straight to EXEC;
    // if that prefetch hit a bus error, FETCH asks again and takes the fault.
    assign to_exec  = complete && !trap_early && !rst && (in_mem || in_md) && !pf_bad;   // = retire there
    // A branch or jalr that completes without a trap fetches in the next
    // cycle, from pc (next_pc registered); so the fetch address never
    // depends on next_pc's late part, only on next_pc_seq.
    wire   fetch_later = in_exec && !trap_early && (is_branch || is_jalr);
    assign fetch_start = !rst && ((complete && !to_exec && !fetch_later) || prefetch || (in_fetch && !fetch_pending));

    // next_pc without the register-dependent targets (taken branch, jalr):
    // the address of a fetch started in the completing cycle.
    assign      next_pc_seq = trap_early              ? trap_target :
                              (in_exec && is_mret)    ? mepc :
                              (in_exec && is_jal)     ? pc_imm : pc_plus4;
    always @(*) begin
        if (br_taken && !trap_early)
            next_pc = branch_misaligned ? trap_target : pc_imm;
        else if (in_exec && is_jalr && !trap_early)
            next_pc = jump_target;
        else
            next_pc = next_pc_seq;
    end

    always @(*) begin
        if (in_mem)
            rf_wdata = load_sub ? load_data : d_rdata;
        else if (in_md)
            rf_wdata = md_result;
        else if (is_lui)
            rf_wdata = imm;
        else if (is_auipc)
            rf_wdata = pc_imm;
        else if (is_jal || is_jalr)
            rf_wdata = pc_plus4;
        else if (is_csr)
            rf_wdata = csr_rdata;
        else
            rf_wdata = alu_result;
    end

    assign dbus_req  = !rst && (exec_mem || (in_mem && !d_done));
    assign dbus_addr = eff_addr;
    assign dbus_we   = is_store;

    always @(posedge clk) begin
        if (rst) begin
            state     <= S_FETCH;
            pc        <= RESET_PC;
            d_done    <= 1'b0;
            md_done_q <= 1'b0;
        end else begin
            // "answered" flags exist only inside MEM / MULDIV, so no stale
            // flag can reach another instruction (and the bus proof in
            // tb/formal/cpu_bus_props.v closes by induction).
            d_done    <= in_mem && !complete && (d_done || dbus_ack);
            md_done_q <= in_md && !complete && (md_done_q || md_done);
            if (in_mem && dbus_ack && !d_done) begin
                d_err_q   <= dbus_err;
                d_rdata_q <= dbus_rdata;
            end
            if (complete) begin
                state     <= to_exec ? S_EXEC : S_FETCH;
                pc        <= next_pc;
            end else begin
                case (state)
                    S_FETCH: if (fetched) state <= S_EXEC;
                    S_EXEC:  state <= exec_mem ? S_MEM : S_MULDIV;
                    default: ;
                endcase
            end
        end
    end
endmodule
`default_nettype wire
