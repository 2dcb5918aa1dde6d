// SPDX-License-Identifier: MIT
`default_nettype none
`include "tl_cpu_bus.vh"
// torqueloop CPU, pipelined: RV32IM + Zicsr, machine mode only.  The same
// ports, CSRs, traps and bus contract as tl_cpu (docs/cpu.md), in four
// stages with the instruction fetch in front of them:
//
//   F  fetch   : ibus request (address f_pc, or the held address of a request
//                not yet answered); every answer lands in a register (L),
//                then moves into a two-entry queue unless D takes it.  A
//                branch target buffer sends the request after a jump it
//                knows to the jump's target (no cycle lost).
//   D  decode  : the landed word (L, or the queue's head when E held):
//                decoded, register file read (block RAM, registered read)
//                and operand choices at the edge into E.  jal and backward
//                branches the BTB did not know are predicted taken: the
//                fetch requests their target in the next cycle (2 cycles
//                lost).
//   E  execute : operands forwarded from M and W, a load's reader waits
//                here, ALU, branch comparator, jump/branch targets (jalr,
//                a taken forward branch or a mispredicted branch redirects
//                the fetch: 3 cycles lost), effective address,
//                multiply/divide (E waits for the unit), every exception
//                but a data bus error, and interrupts, taken before the
//                instruction in E executes.
//   M  memory  : the data bus request, from registers.
//   W  write   : the data bus answer (a wait state stalls the pipeline),
//                CSR instructions, mret and fence.i, trap entry; the one
//                point where instructions retire, write rd and change
//                architectural state, so traps are precise: an instruction
//                that traps in W has no effect, and nothing younger has had
//                any (a younger access in M is held off the bus while W
//                traps or ends in a CSR/mret/fence.i, all of which flush the
//                pipeline and refetch).
//
// Bus contract: tl_cpu's (docs/cpu.md), and a new request may start in an
// ack cycle.  With a slave that takes a request in its own ack cycle (ack
// <= req, see tb/cpu/cpu_sim_top.v PIPELINED) each bus moves one word per
// cycle; with one that does not (ack <= req & ~ack, rtl/soc/tl_soc_fabric.v)
// the core works unchanged at one word every two cycles.
// Parameters and ports: `CPU_CORE_PARAMS and `CPU_CORE_PORTS of tl_cpu_bus.vh.
module tl_cpu_pipe #(`CPU_CORE_PARAMS) (`CPU_CORE_PORTS);
`include "tl_cpu_causes.vh"

    // Control signals used before the stage that drives them.
    wire        gs;              // global stall: W waits for its data bus answer
    wire        flush_w;         // W redirects: trap, mret, CSR, fence.i
    wire [31:0] redirect_w_pc;
    wire        redirect_e;      // E redirects: taken branch, jal, jalr
    wire        redirect    = flush_w || redirect_e;   // kills D (and E, M for flush_w)
    wire        redirect_d;      // D predicts a jump taken: jal, or a branch backwards
    wire        refetch     = redirect || redirect_d;  // the queue and the answer awaited are stale
    // W's redirect writes f_pc in its own cycle; D's and E's are requested
    // in the next cycle from registers (pend_*), which keeps the instruction
    // word (D) and the branch comparator (E) off the fetch address: the
    // request comes a cycle after the decision, as it did when the decision
    // wrote f_pc, so no cycle is lost.
    reg         pend_d;          // D predicted a jump last cycle: its target is E's pc + imm now
    reg         pend_e;          // E redirected last cycle: to pend_e_pc
    reg  [31:0] pend_e_pc;
    wire        pend = pend_d || pend_e;
    wire [31:0] pend_pc;

    // ==== F: instruction fetch =================================================================
    reg         f_out;           // a request is outstanding (presented before, not answered yet)
    reg  [31:0] f_out_addr;
    reg         f_discard;       // its answer belongs to a flushed path
    reg  [31:0] f_pc;            // the next address to request
    // Every answer lands in the landing register l_*, with nothing in front
    // of it but the bus, so the block RAM's output (in the SoC, its mux
    // tree and the fabric's) reaches a flip-flop before any decode: the
    // RAM's clock-to-out and its wire take most of a 60 MHz cycle on the
    // proxy.  D decodes the older of the queue's head and the landed word;
    // a landed word D does not take moves into the 2-entry queue (or waits
    // in place while the queue is full, when no answer can be coming).
    reg         l_valid;
    reg  [31:0] l_insn, l_pc;
    reg         l_err, l_btb;
    reg  [1:0]  q_n;
    reg  [31:0] q_insn0, q_insn1, q_pc0, q_pc1;
    reg         q_err0, q_err1;
    reg         f_out_btb, q_btb0, q_btb1;   // the word's successor was fetched from the BTB's target
    reg         q_pred0, q_pred1;            // the word is predicted taken (pred_of)

    // Branch target buffer: the jumps D predicted (jal, backward branches),
    // BTB_N entries indexed by pc[BTB_IB+1:2], looked up on f_pc when a
    // sequential request goes out, so the request after a predicted jump
    // already goes to its target (no cycle lost; D would lose one).  The
    // lookup starts from registers and ends in f_pc: nothing is added in
    // front of the fetch address.  An entry is a function of the word at its
    // pc: a store that retires to that word drops it, fence.i and reset drop
    // all.  Direction is still checked in E (a loop's exit is a wrong guess).
    // Intel template: none for block RAM - its tables have an asynchronous
    // read, which goes to MLAB or registers (Quartus Prime Recommended HDL
    // Coding Styles, "Use Synchronous Memory Blocks"), fine at 8 entries.
    localparam integer BTB_IB = 3;
    localparam integer BTB_N  = 1 << BTB_IB;
    reg  [BTB_N-1:0]  btb_v;
    reg  [31:BTB_IB+2] btb_tag [0:BTB_N-1];
    reg  [31:2]       btb_tgt [0:BTB_N-1];
    wire [BTB_IB-1:0] f_bi   = f_pc[BTB_IB+1:2];
    wire              f_bhit = btb_v[f_bi] && btb_tag[f_bi] == f_pc[31:BTB_IB+2];
    wire [31:2]       f_btgt = btb_tgt[f_bi];

    wire resp   = f_out && ibus_ack && !f_discard;     // an answer for the current path
    wire f_hold = f_out && !ibus_ack;
    // Room for the answer of a new request (next cycle at the earliest),
    // whatever D does meanwhile: the queue and L hold at most
    // q_n + l_valid + resp words after this edge, and three fit.
    wire [2:0] f_words = {1'b0, q_n} + {2'b0, l_valid} + {2'b0, resp};
    wire f_room = f_words <= 3'd2;
    wire f_new  = !f_hold && f_room;
    assign ibus_req  = !rst && (f_hold || f_new);
    assign ibus_addr = f_hold ? f_out_addr : (pend ? pend_pc : f_pc);

    // ==== D: decode ================================================================================
    wire        d_q     = q_n != 2'd0;        // the queue's head, else the landed word
    wire        d_valid = d_q || l_valid;
    wire [31:0] d_insn  = d_q ? q_insn0 : l_insn;
    wire [31:0] d_pc    = d_q ? q_pc0 : l_pc;
    wire        d_ferr  = d_q ? q_err0 : l_err;
    wire        d_btb   = d_q ? q_btb0 : l_btb;

    wire [4:0]  d_rd, d_rs1;
    wire [2:0]  d_funct3;
    wire [31:0] d_imm;
    wire [16:0] d_flags;
    tl_cpu_decode u_decode (
        .insn(d_insn), .rd(d_rd), .rs1(d_rs1), .funct3(d_funct3), .imm(d_imm), .flags(d_flags)
    );
    wire [4:0] d_rs2      = d_insn[24:20];
    wire [6:0] d_opcode   = d_insn[6:0];
    wire d_fencei   = d_opcode == 7'b0001111 && d_funct3 == 3'b001;

    reg        e_valid, m_valid, w_valid;
    reg        e_late, m_late, w_late;         // a load or CSR instruction that writes rd
    reg  [4:0] e_rd, m_rd;
    // which source registers the instruction reads (a needless hazard costs a cycle)
    wire d_uses_rs1 = d_opcode != 7'b0110111 && d_opcode != 7'b0010111 && d_opcode != 7'b1101111;
    wire d_uses_rs2 = d_opcode == 7'b1100011 || d_opcode == 7'b0100011 || d_opcode == 7'b0110011;
    /* verilator lint_off UNUSEDSIGNAL */  // w: the fields the function reads
    // Static prediction: jal always, a conditional branch when it jumps
    // backwards (a loop); not a target that would trap as misaligned (E
    // raises that; immediate bit 1 is insn[21] for jal, insn[8] for a
    // branch).  E checks every prediction and corrects a wrong one.
    function pred_of(input [31:0] w);
        pred_of = (w[6:0] == 7'b1101111 && !w[21]) || (w[6:0] == 7'b1100011 && w[31] && !w[8]);
    endfunction
    /* verilator lint_on UNUSEDSIGNAL */
    // for the queue's head and the landed word apart, the choice last (the
    // prediction steers the queue and the fetch)
    wire l_pred   = pred_of(l_insn);
    wire d_pred   = d_q ? q_pred0 : l_pred;

    // D never waits: whatever the word is, it moves on when E takes it, so
    // no decision of D's depends on the instruction word but the prediction
    wire e_load;                                // E takes a new instruction (or a bubble) this edge
    wire d_go = d_valid && e_load;              // D moves on (unless a redirect kills it)
    wire [1:0] q_left = q_n - {1'b0, d_go && d_q};   // the queue's words D leaves
    wire l_take = d_go && !d_q;                       // D takes the landed word
    wire l_in   = l_valid && !l_take && q_left != 2'd2;   // the landed word moves into the queue
    assign redirect_d    = d_go && d_pred && !d_btb && !redirect;

    // ==== register file =====================================================================
    wire        rf_we;
    wire [4:0]  rf_waddr;
    reg  [31:0] rf_wdata;
    wire [31:0] rf_word1, rf_word2;
    /* verilator lint_off PINCONNECTEMPTY */
    tl_cpu_regfile u_regfile (
        .clk(clk), .we(rf_we), .waddr(rf_waddr), .wdata(rf_wdata),
        .re(e_load), .raddr1(d_rs1), .raddr2(d_rs2),
        .rdata1(), .rdata2(), .word1(rf_word1), .word2(rf_word2)
    );
    /* verilator lint_on PINCONNECTEMPTY */

    // ==== E: execute ==============================================================================
    reg  [31:0] e_pc, e_insn, e_imm;
    reg  [4:0]  e_rs1, e_rs2;
    reg         e_use1, e_use2;  // it reads rs1, rs2
    reg  [2:0]  e_funct3;
    reg         e_ferr, e_fencei;
    reg         e_lui, e_auipc, e_jal, e_jalr, e_branch, e_is_load, e_is_store, e_alt;
    reg         e_use_imm;       // the ALU's second operand is the immediate (D chose it: ob_sel)
    reg         e_md, e_csr, e_csr_writes, e_ecall, e_ebreak, e_mret, e_writes, e_illegal;
    reg         e_md_started, e_md_fin;
    reg         e_pred;          // D predicted it taken and fetched its target

    // Forwarding: M's and W's early results (ALU, jumps, lui/auipc,
    // multiply/divide).  The choice is made in D, beside the register file
    // read, and registered (below): the instruction in E moves to M and the
    // one in M to W in the edge D moves to E, so D compares with them; E
    // then starts from flip-flops.  What D knows in that edge is chosen
    // there into o*_pre: M's result (W's in E), the register file's write
    // in that edge, x0, and for the ALU's second operand the immediate; E
    // has one choice left in front of its adders and comparator (M's
    // result, o*_pre or the bank's word).  (E stays longer only for a
    // multiply/divide, which takes its operands in its first cycle, or when
    // the whole pipeline waits, which keeps M and W as they are.)
    reg         m_early;
    reg  [31:0] m_result, w_result;
    reg  [4:0]  w_rd;
    reg         f1m, f2m, fbm;              // M's result
    reg         o1_sel, o2_sel, ob_sel;     // else o*_pre, else the bank's word
    reg  [31:0] o1_pre, o2_pre, ob_pre;
    wire [31:0] rs1v  = f1m ? m_result : (o1_sel ? o1_pre : rf_word1);
    wire [31:0] rs2v  = f2m ? m_result : (o2_sel ? o2_pre : rf_word2);
    wire [31:0] alu_b = fbm ? m_result : (ob_sel ? ob_pre : rf_word2);   // rs2 or the immediate

    // Load-use hazard: a load's word (or a CSR's old value) reaches rd only
    // in W, and is not forwarded from there into E (that would put a block
    // RAM's output in front of the ALU).  Its reader waits in E (not in D,
    // whose decisions would then wait for the word's register numbers) while
    // the load is in M or W; in the edge W writes the register, the
    // reader's operand register takes the word (o*_pre, below), so a load
    // and its use cost 2 cycles more, with one instruction between 1.
    wire e_hz = (e_use1 && ((m_valid && m_late && m_rd == e_rs1) || (w_valid && w_late && w_rd == e_rs1))) ||
                (e_use2 && ((m_valid && m_late && m_rd == e_rs2) || (w_valid && w_late && w_rd == e_rs2)));

    wire [31:0] alu_result;
    wire        branch_taken;
    tl_cpu_alu u_alu (
        .funct3(e_funct3), .alt(e_alt), .a(rs1v), .b(alu_b),
        .result(alu_result), .cmp_a(rs1v), .cmp_b(rs2v), .branch_taken(branch_taken)
    );
    wire [31:0] e_pc4    = e_pc + 32'd4;
    wire [31:0] e_pc_imm = e_pc + e_imm;
    wire [31:0] e_eff    = rs1v + e_imm;
    wire [31:0] e_jtarget = e_jalr ? {e_eff[31:1], 1'b0} : e_pc_imm;
    wire        e_taken  = e_branch && branch_taken;

    wire        e_misaligned;
    wire [3:0]  e_be;
    wire [31:0] e_wdata;
    /* verilator lint_off PINCONNECTEMPTY */
    tl_cpu_lsu u_lsu_e (
        .funct3(e_funct3), .off(e_eff[1:0]), .store_data(rs2v),
        .misaligned(e_misaligned), .be(e_be), .wdata(e_wdata), .rdata(32'd0), .load_data()
    );
    /* verilator lint_on PINCONNECTEMPTY */

    // Exceptions of E, in the priority of tl_cpu: fetch fault, interrupt,
    // illegal, ecall, ebreak, misaligned jump, misaligned access, misaligned
    // taken branch.
    wire        irq_pending;
    wire [3:0]  irq_code;
    reg         e_trap, e_irq;
    reg  [3:0]  e_code;
    reg  [31:0] e_tval;
    always @(*) begin
        e_trap = 1'b1;
        e_irq  = 1'b0;
        e_code = CAUSE_FETCH_MISALIGNED;
        e_tval = 32'd0;
        if (e_ferr) begin
            e_code = CAUSE_FETCH_FAULT; e_tval = e_pc;
        end else if (irq_pending) begin
            e_irq = 1'b1; e_code = irq_code;
        end else if (e_illegal) begin
            e_code = CAUSE_ILLEGAL; e_tval = e_insn;
        end else if (e_ecall) begin
            e_code = CAUSE_ECALL_M;
        end else if (e_ebreak) begin
            e_code = CAUSE_BREAKPOINT; e_tval = e_pc;
        end else if ((e_jal || e_jalr) && e_jtarget[1]) begin
            e_code = CAUSE_FETCH_MISALIGNED; e_tval = e_jtarget;
        end else if ((e_is_load || e_is_store) && e_misaligned) begin
            e_code = e_is_store ? CAUSE_STORE_MISALIGNED : CAUSE_LOAD_MISALIGNED; e_tval = e_eff;
        end else if (e_taken && e_pc_imm[1]) begin
            e_code = CAUSE_FETCH_MISALIGNED; e_tval = e_pc_imm;
        end else begin
            e_trap = 1'b0;
        end
    end

    // multiply / divide: started in E's first cycle, E waits for the result
    // (a multiply leaves E in the unit's last cycle, with the result from its
    // adders); an interrupt abandons it (re-executed after mret)
    wire        md_done, md_last;
    wire [31:0] md_result, md_word;
    wire        in_md    = e_valid && e_md && e_md_started;   // a multiply/divide in progress
    // the exceptions a multiply/divide can have (no address, no target): kept
    // apart from e_trap, so that the pipeline's enables do not wait for E's adders
    wire        md_trap  = e_ferr || irq_pending;
    wire        md_start = e_valid && e_md && !e_md_started && !md_trap && !flush_w && !e_hz;
    /* verilator lint_off PINCONNECTEMPTY */
    tl_cpu_muldiv #(.RADIX4(1)) u_muldiv (
        .clk(clk), .rst(rst), .start(md_start), .abort(flush_w || (in_md && md_trap && !gs)),
        .funct3(e_funct3), .a(rs1v), .b(rs2v), .busy(), .done(md_done), .result(md_result),
        .mul_last(md_last), .mul_word(md_word)
    );
    /* verilator lint_on PINCONNECTEMPTY */
    // (the unit's done pulse after a multiply that left in its last cycle
    // belongs to no instruction: only a started operation's counts)
    wire md_fin = in_md && (md_done || md_last);
    wire e_done = !e_hz && (!e_md || md_trap || md_fin || e_md_fin);
    wire e_adv  = e_valid && e_done && !gs && !flush_w;   // E moves to M
    assign e_load = !gs && (!e_valid || e_done);
    // a jump or taken branch D did not predict, or a predicted branch not
    // taken.  Also for an instruction that traps: W's trap redirects again
    // (and keeps the trap logic out of the fetch address).
    assign redirect_e    = e_valid && !gs && !e_hz &&
                           (e_jalr || (e_jal && !e_pred) || (e_branch && e_taken != e_pred));
    // where to: known without the comparator (a branch redirects only
    // against its prediction: predicted taken, it falls through)
    wire [31:0] redirect_e_pc = (e_branch && e_pred) ? e_pc4 : e_jtarget;
    // D's prediction moved its jump into E (nothing can hold E in that edge)
    assign pend_pc = pend_e ? pend_e_pc : e_pc_imm;

    reg [31:0] e_result;
    always @(*) begin
        if (e_lui)
            e_result = e_imm;
        else if (e_auipc)
            e_result = e_pc_imm;
        else if (e_md)
            e_result = md_last ? md_word : md_result;
        else if (e_jal || e_jalr || e_csr || e_mret || e_fencei)
            e_result = e_pc4;               // the link, or where W refetches from
        else
            e_result = alu_result;
    end

    // ==== M: data bus request ======================================================================
    reg  [31:0] m_pc, m_insn, m_addr, m_wdata, m_tval, m_csr_src;
    reg  [3:0]  m_be, m_code;
    reg  [2:0]  m_funct3;
    reg         m_load, m_store, m_trap, m_irq, m_wr, m_csr, m_csr_writes, m_mret, m_fencei;
    wire        m_acc = m_valid && (m_load || m_store) && !m_trap;

    // ==== W: retire ================================================================================
    reg  [31:0] w_pc, w_insn, w_addr, w_wdata, w_tval, w_csr_src;
    reg  [3:0]  w_be, w_code;
    reg  [2:0]  w_funct3;
    reg         w_load, w_store, w_acc, w_trap, w_irq, w_wr, w_csr, w_csr_writes, w_mret, w_fencei;

    wire        csr_illegal;
    assign gs = w_valid && w_acc && !dbus_ack;
    // W ends in a flush (or faults on the bus): M's access must not start
    wire w_csr_flush = w_csr && (w_csr_writes || csr_illegal);
    wire w_block = w_valid && (w_trap || w_csr_flush || w_mret || w_fencei || (w_acc && dbus_err));
    assign dbus_req   = !rst && (gs || (m_acc && !w_block));
    assign dbus_addr  = gs ? w_addr  : m_addr;
    assign dbus_we    = gs ? w_store : m_store;
    assign dbus_be    = gs ? w_be    : m_be;
    assign dbus_wdata = gs ? w_wdata : m_wdata;

    wire [31:0] csr_rdata, trap_target, mepc;
    wire        w_done    = w_valid && !gs;
    wire        bus_fault = w_acc && dbus_err;           // with dbus_ack (w_done)
    wire        csr_bad   = w_csr && csr_illegal;
    wire        take_trap = w_done && (w_trap || bus_fault || csr_bad);
    wire [3:0]  trap_code = w_trap ? w_code : (bus_fault ? (w_store ? CAUSE_STORE_FAULT : CAUSE_LOAD_FAULT)
                                                         : CAUSE_ILLEGAL);
    wire [31:0] trap_tval = w_trap ? w_tval : (bus_fault ? w_addr : w_insn);
    assign retire  = w_done && !take_trap && !rst;
    // a CSR instruction that only reads changes nothing: no refetch
    assign flush_w = take_trap || (retire && ((w_csr && w_csr_writes) || w_mret || w_fencei));
    assign redirect_w_pc = take_trap ? trap_target : (w_mret ? mepc : w_result);

    tl_cpu_csr #(.HART_ID(HART_ID)) u_csr (
        .clk(clk), .rst(rst),
        .addr(w_insn[31:20]), .op(w_funct3[1:0]), .src(w_csr_src),
        .writes(w_csr_writes), .commit(retire && w_csr),
        .rdata(csr_rdata), .illegal(csr_illegal),
        .trap(take_trap && !rst), .trap_irq(w_trap && w_irq), .trap_code(trap_code), .trap_pc(w_pc),
        .trap_tval(trap_tval), .trap_target(trap_target),
        .mret(retire && w_mret), .mepc_out(mepc),
        `CPU_IRQ_CONNECT, .irq_pending(irq_pending), .irq_code(irq_code), .retire(retire)
    );

    wire [31:0] load_data;
    /* verilator lint_off PINCONNECTEMPTY */
    tl_cpu_lsu u_lsu_w (
        .funct3(w_funct3), .off(w_addr[1:0]), .store_data(32'd0),
        .misaligned(), .be(), .wdata(), .rdata(dbus_rdata), .load_data(load_data)
    );
    /* verilator lint_on PINCONNECTEMPTY */
    assign rf_we    = retire && w_wr;
    assign rf_waddr = w_rd;
    always @(*) begin
        if (w_load)
            rf_wdata = load_data;
        else if (w_csr)
            rf_wdata = csr_rdata;
        else
            rf_wdata = w_result;
    end

    // ==== pipeline registers =====================================================================
    wire e_writes_nz = e_writes && e_rd != 5'd0;
    wire btb_we = pend_d && !e_ferr;       // (a word that faulted predicts nothing)
    // D's operand choices (see Forwarding): M's result, the register file's write in this edge
    wire        d_w1 = m_valid && m_early && m_rd == d_rs1;
    wire        d_w2 = m_valid && m_early && m_rd == d_rs2;
    wire        d_rf1 = rf_we && rf_waddr == d_rs1;
    wire        d_rf2 = rf_we && rf_waddr == d_rs2;
    // The operand registers' next values: D's choices (e_load), or, while E
    // holds, M's result or the register file's write as they pass.  A load's
    // word (W's bus answer through the byte lanes) is the last choice in
    // front of each register, its select from registers: in the SoC the
    // block RAM's output and its mux tree take most of a cycle already.
    wire [31:0] rf_wdata_nl = w_csr ? csr_rdata : w_result;   // W's write when it is no load
    wire        e_hold = !e_load && !gs;
    wire        h1m = m_valid && m_early && m_rd == e_rs1;
    wire        h2m = m_valid && m_early && m_rd == e_rs2;
    wire        h1r = rf_we && rf_waddr == e_rs1;
    wire        h2r = rf_we && rf_waddr == e_rs2;
    wire        o1_we = e_load || (e_hold && (h1m || h1r));
    wire        o2_we = e_load || (e_hold && (h2m || h2r));
    wire        ob_we = e_load || (e_hold && !e_use_imm && (h2m || h2r));
    // (where the register file's write is not chosen, the register's select is 0)
    wire        o1_ld = w_load && (e_load ? !d_w1 && d_rs1 != 5'd0 : !h1m);
    wire        o2_ld = w_load && (e_load ? !d_w2 && d_rs2 != 5'd0 : !h2m);
    wire        ob_ld = w_load && (e_load ? !d_flags[7] && !d_w2 && d_rs2 != 5'd0 : !h2m);
    wire [31:0] o2_d  = d_w2 ? m_result : (d_rs2 == 5'd0 ? 32'd0 : rf_wdata_nl);
    wire [31:0] o1_nl = e_load ? (d_w1 ? m_result : (d_rs1 == 5'd0 ? 32'd0 : rf_wdata_nl))
                               : (h1m ? m_result : rf_wdata_nl);
    wire [31:0] o2_nl = e_load ? o2_d : (h2m ? m_result : rf_wdata_nl);
    wire [31:0] ob_nl = e_load ? (d_flags[7] ? d_imm : o2_d) : (h2m ? m_result : rf_wdata_nl);
    wire w_btb_same = btb_tag[w_addr[BTB_IB+1:2]] == w_addr[31:BTB_IB+2];   // W's store hits an entry's word
    // E's result can be forwarded from M (the trap check is left out: a
    // trapping instruction's readers never retire)
    wire e_early = e_writes_nz && !e_is_load && !e_csr;
    always @(posedge clk) begin
        if (rst) begin
            f_out     <= 1'b0;
            f_discard <= 1'b0;
            f_pc      <= RESET_PC;
            pend_d    <= 1'b0;
            pend_e    <= 1'b0;
            btb_v     <= {BTB_N{1'b0}};
            q_n       <= 2'd0;
            l_valid   <= 1'b0;
            e_valid   <= 1'b0;
            m_valid   <= 1'b0;
            w_valid   <= 1'b0;
            e_md_started <= 1'b0;
            e_md_fin  <= 1'b0;
        end else begin
            // ---- F ----
            f_out      <= ibus_req;
            f_out_addr <= ibus_addr;
            pend_d    <= redirect_d;
            pend_e    <= redirect_e && !flush_w;
            pend_e_pc <= redirect_e_pc;
            if (flush_w)
                f_pc <= redirect_w_pc;
            else if (pend)
                f_pc <= f_new ? pend_pc + 32'd4 : pend_pc;
            else if (f_new)
                f_pc <= f_bhit ? {f_btgt, 2'b00} : f_pc + 32'd4;
            if (!f_hold)
                f_out_btb <= !pend && f_bhit;
            // ---- BTB: D's prediction is written when its target is known (E's pc + imm) ----
            if (btb_we)
                btb_v[e_pc[BTB_IB+1:2]] <= 1'b1;
            if (retire && w_fencei)
                btb_v <= {BTB_N{1'b0}};
            else if (retire && w_store && w_btb_same)
                btb_v[w_addr[BTB_IB+1:2]] <= 1'b0;
            if (refetch)
                f_discard <= ibus_req;
            else if (ibus_ack)
                f_discard <= 1'b0;
            // ---- instruction queue: D takes the head; the landed word goes in ----
            // behind what is left.  The words load whatever a redirect does
            // (it only empties the queue and L).
            if (!l_valid || l_take || l_in) begin   // (else the queue is full and no answer comes: L waits)
                l_insn <= ibus_rdata; l_pc <= f_out_addr; l_err <= ibus_err; l_btb <= f_out_btb;
            end
            if (refetch)
                l_valid <= 1'b0;
            else
                l_valid <= resp || (l_valid && !l_take && !l_in);
            if (l_in && q_left == 2'd0) begin
                q_insn0 <= l_insn; q_pc0 <= l_pc; q_err0 <= l_err; q_btb0 <= l_btb; q_pred0 <= l_pred;
            end else if (d_go && d_q) begin
                q_insn0 <= q_insn1; q_pc0 <= q_pc1; q_err0 <= q_err1; q_btb0 <= q_btb1; q_pred0 <= q_pred1;
            end
            if (l_in && q_left == 2'd1) begin
                q_insn1 <= l_insn; q_pc1 <= l_pc; q_err1 <= l_err; q_btb1 <= l_btb; q_pred1 <= l_pred;
            end
            if (refetch)
                q_n <= 2'd0;
            else
                q_n <= q_left + {1'b0, l_in};
            // ---- D -> E ----
            if (e_load) begin
                e_valid <= d_go && !redirect;
                e_md_started <= 1'b0;
                e_md_fin <= 1'b0;
            end else if (flush_w) begin
                e_valid <= 1'b0;
            end else begin
                if (md_start)
                    e_md_started <= 1'b1;
                if (in_md && md_done)
                    e_md_fin <= 1'b1;
            end
            if (e_load) begin
                e_pc <= d_pc; e_insn <= d_insn; e_imm <= d_imm; e_rs1 <= d_rs1; e_rd <= d_rd;
                e_rs2 <= d_rs2; e_use1 <= d_uses_rs1; e_use2 <= d_uses_rs2;
                e_funct3 <= d_funct3; e_ferr <= d_ferr; e_fencei <= d_fencei; e_pred <= d_pred;
                {e_illegal, e_writes, e_mret, e_ebreak, e_ecall, e_csr_writes, e_csr, e_md, e_alt,
                 e_use_imm, e_is_store, e_is_load, e_branch, e_jalr, e_jal, e_auipc, e_lui} <= d_flags;
                e_late <= (d_flags[5] || d_flags[10]) && d_flags[15] && d_rd != 5'd0;
                f1m <= e_valid && e_early && e_rd == d_rs1;
                f2m <= e_valid && e_early && e_rd == d_rs2;
                fbm <= e_valid && e_early && e_rd == d_rs2 && !d_flags[7];
                o1_sel <= d_w1 || d_rs1 == 5'd0 || d_rf1;
                o2_sel <= d_w2 || d_rs2 == 5'd0 || d_rf2;
                ob_sel <= d_flags[7] || d_w2 || d_rs2 == 5'd0 || d_rf2;
            end else if (!gs) begin
                // E holds (a hazard, a multiply/divide): M's result moves to
                // W and W writes the register file, so the operands follow
                f1m <= 1'b0;
                f2m <= 1'b0;
                fbm <= 1'b0;
                if (h1m || h1r)
                    o1_sel <= 1'b1;
                if (h2m || h2r)
                    o2_sel <= 1'b1;
                if (!e_use_imm && (h2m || h2r))
                    ob_sel <= 1'b1;
            end
            if (o1_we)
                o1_pre <= o1_ld ? load_data : o1_nl;
            if (o2_we)
                o2_pre <= o2_ld ? load_data : o2_nl;
            if (ob_we)
                ob_pre <= ob_ld ? load_data : ob_nl;
            // ---- E -> M ----
            if (!gs) begin
                m_valid <= e_adv;
                m_pc <= e_pc; m_insn <= e_insn; m_rd <= e_rd; m_funct3 <= e_funct3;
                m_result <= e_result;
                m_addr <= e_eff; m_be <= e_be; m_wdata <= e_wdata;
                m_load <= e_is_load; m_store <= e_is_store;
                m_trap <= e_trap; m_irq <= e_irq; m_code <= e_code; m_tval <= e_tval;
                m_wr <= e_writes_nz;
                m_early <= e_early;
                m_late  <= e_late;
                m_csr <= e_csr; m_csr_writes <= e_csr_writes; m_mret <= e_mret; m_fencei <= e_fencei;
                m_csr_src <= e_funct3[2] ? {27'd0, e_rs1} : rs1v;
            end
            // ---- M -> W ----
            if (!gs) begin
                w_valid <= m_valid && !flush_w;
                w_pc <= m_pc; w_insn <= m_insn; w_rd <= m_rd; w_funct3 <= m_funct3; w_late <= m_late;
                w_result <= m_result;
                w_addr <= m_addr; w_be <= m_be; w_wdata <= m_wdata;
                w_load <= m_load; w_store <= m_store; w_acc <= m_acc;
                w_trap <= m_trap; w_irq <= m_irq; w_code <= m_code; w_tval <= m_tval;
                w_wr <= m_wr;
                w_csr <= m_csr; w_csr_writes <= m_csr_writes; w_mret <= m_mret; w_fencei <= m_fencei;
                w_csr_src <= m_csr_src;
            end
        end
    end

    always @(posedge clk) begin
        if (btb_we) begin
            btb_tag[e_pc[BTB_IB+1:2]] <= e_pc[31:BTB_IB+2];
            btb_tgt[e_pc[BTB_IB+1:2]] <= e_pc_imm[31:2];
        end
    end
endmodule
`default_nettype wire
