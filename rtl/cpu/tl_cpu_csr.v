// SPDX-License-Identifier: MIT
`default_nettype none
`include "tl_cpu_bus.vh"
// Machine-mode CSRs (privileged spec, M-mode only), trap entry and mret.
//
// Implemented: mstatus (MIE, MPIE; MPP reads 11), misa (RV32IM, read-only),
// mie/mip (MSI 3, MTI 7, MEI 11), mtvec (direct and vectored), mscratch,
// mepc, mcause, mtval, mcycle(h), minstret(h), mvendorid/marchid/mimpid (0),
// mhartid, and the user read-only shadows cycle(h), instret(h), time(h).
// Any other address, or a write to a read-only address (addr[11:10] = 11),
// is reported as `illegal` so the core raises an illegal-instruction trap.
module tl_cpu_csr #(
    parameter [31:0] HART_ID = 32'd0
) (
    input  wire        clk,
    input  wire        rst,
    // CSR instruction in the execute cycle
    input  wire [11:0] addr,
    input  wire [1:0]  op,          // funct3[1:0]: 01 write, 10 set, 11 clear
    input  wire [31:0] src,         // rs1 value or zero-extended zimm
    input  wire        writes,      // the instruction writes the CSR
    input  wire        commit,      // the instruction completes this cycle
    output reg  [31:0] rdata,
    output wire        illegal,
    // trap entry / return (one-cycle pulses, mutually exclusive with commit)
    input  wire        trap,
    input  wire        trap_irq,    // 1: interrupt, 0: exception
    input  wire [3:0]  trap_code,
    input  wire [31:0] trap_pc,
    input  wire [31:0] trap_tval,
    output wire [31:0] trap_target, // where the handler starts (valid with trap_irq/trap_code)
    input  wire        mret,
    output wire [31:0] mepc_out,
    // interrupts (levels, synchronous to clk) and the machine timer (the time CSRs)
    `CPU_IRQ_PORTS(input),
    output wire        irq_pending,
    output wire [3:0]  irq_code,
    // instruction counter
    input  wire        retire
);
    reg        mstatus_mie, mstatus_mpie;
    reg        mie_msie, mie_mtie, mie_meie;
    reg [31:0] mtvec, mscratch, mepc, mcause, mtval;
    reg [31:0] mcycle_lo, mcycle_hi, minstret_lo, minstret_hi;

    wire [31:0] mstatus = {19'd0, 2'b11, 3'd0, mstatus_mpie, 3'd0, mstatus_mie, 3'd0};
    wire [31:0] mip     = {20'd0, irq_external, 3'd0, irq_timer, 3'd0, irq_software, 3'd0};
    wire [31:0] mie     = {20'd0, mie_meie, 3'd0, mie_mtie, 3'd0, mie_msie, 3'd0};
    localparam [31:0] MISA = 32'h4000_1100;  // MXL=1 (RV32), extensions I and M

    reg known;
    always @(*) begin
        known = 1'b1;
        case (addr)
            12'h300: rdata = mstatus;
            12'h301: rdata = MISA;
            12'h304: rdata = mie;
            12'h305: rdata = mtvec;
            12'h340: rdata = mscratch;
            12'h341: rdata = mepc;
            12'h342: rdata = mcause;
            12'h343: rdata = mtval;
            12'h344: rdata = mip;
            12'hB00, 12'hC00: rdata = mcycle_lo;
            12'hB80, 12'hC80: rdata = mcycle_hi;
            12'hB02, 12'hC02: rdata = minstret_lo;
            12'hB82, 12'hC82: rdata = minstret_hi;
            12'hC01: rdata = mtime[31:0];
            12'hC81: rdata = mtime[63:32];
            12'hF11, 12'hF12, 12'hF13: rdata = 32'd0;
            12'hF14: rdata = HART_ID;
            default: begin
                rdata = 32'd0;
                known = 1'b0;
            end
        endcase
    end
    assign illegal = !known || (writes && addr[11:10] == 2'b11);

    reg [31:0] wval;
    always @(*) begin
        case (op)
            2'b01:   wval = src;
            2'b10:   wval = rdata | src;
            default: wval = rdata & ~src;
        endcase
    end
    wire wr = commit && writes;

    // Interrupt priority of the privileged spec: MEI > MSI > MTI.
    wire mei = irq_external && mie_meie;
    wire msi = irq_software && mie_msie;
    wire mti = irq_timer && mie_mtie;
    assign irq_pending = mstatus_mie && (mei || msi || mti);
    assign irq_code    = mei ? 4'd11 : (msi ? 4'd3 : 4'd7);

    // Vectored mode sends interrupts to BASE + 4 * cause, exceptions to BASE.
    assign trap_target = {mtvec[31:2], 2'b00} +
                         ((mtvec[0] && trap_irq) ? {26'd0, trap_code, 2'b00} : 32'd0);
    assign mepc_out = mepc;

    always @(posedge clk) begin
        if (rst) begin
            mstatus_mie  <= 1'b0;
            mstatus_mpie <= 1'b0;
            mie_msie <= 1'b0;
            mie_mtie <= 1'b0;
            mie_meie <= 1'b0;
            mtvec    <= 32'd0;
            mscratch <= 32'd0;
            mepc     <= 32'd0;
            mcause   <= 32'd0;
            mtval    <= 32'd0;
        end else if (trap) begin
            mepc         <= trap_pc;
            mcause       <= {trap_irq, 27'd0, trap_code};
            mtval        <= trap_tval;
            mstatus_mpie <= mstatus_mie;
            mstatus_mie  <= 1'b0;
        end else if (mret) begin
            mstatus_mie  <= mstatus_mpie;
            mstatus_mpie <= 1'b1;
        end else if (wr) begin
            case (addr)
                12'h300: begin
                    mstatus_mie  <= wval[3];
                    mstatus_mpie <= wval[7];
                end
                12'h304: begin
                    mie_msie <= wval[3];
                    mie_mtie <= wval[7];
                    mie_meie <= wval[11];
                end
                // MODE 2 and 3 are reserved: keep only bit 0 (direct/vectored)
                12'h305: mtvec    <= {wval[31:2], 1'b0, wval[0]};
                12'h340: mscratch <= wval;
                12'h341: mepc     <= {wval[31:2], 2'b00};
                12'h342: mcause   <= wval;
                12'h343: mtval    <= wval;
                default: ;
            endcase
        end
    end

    // 64-bit counters as two 32-bit halves: the high half steps on the low
    // half's wrap, so no 64-bit carry chain.  A CSR write wins over the step.
    always @(posedge clk) begin
        if (rst) begin
            mcycle_lo   <= 32'd0;
            mcycle_hi   <= 32'd0;
            minstret_lo <= 32'd0;
            minstret_hi <= 32'd0;
        end else begin
            mcycle_lo <= mcycle_lo + 32'd1;
            if (mcycle_lo == 32'hFFFF_FFFF)
                mcycle_hi <= mcycle_hi + 32'd1;
            // A write to minstret(h) replaces the writing instruction's own count.
            if (retire && !(wr && (addr == 12'hB02 || addr == 12'hB82))) begin
                minstret_lo <= minstret_lo + 32'd1;
                if (minstret_lo == 32'hFFFF_FFFF)
                    minstret_hi <= minstret_hi + 32'd1;
            end
            if (wr) begin
                case (addr)
                    12'hB00: mcycle_lo   <= wval;
                    12'hB80: mcycle_hi   <= wval;
                    12'hB02: minstret_lo <= wval;
                    12'hB82: minstret_hi <= wval;
                    default: ;
                endcase
            end
        end
    end
endmodule
`default_nettype wire
