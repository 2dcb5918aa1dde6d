// SPDX-License-Identifier: MIT
// the register map's TL_* names (generated; the include guard makes a second include empty)
`include "regmap.vh"
`include "tl_cpu_bus.vh"
`default_nettype none
// Test harness of the CPU (simulation only, not part of the SoC): the core,
// a two-port RAM, a boot ROM stub, the SoC's own machine timer and interrupt
// controller (rtl/soc/tl_soc_timer.v, tl_soc_intc.v) and the counters the
// ELF runner reports.  The memory map is the SoC's, from the register map's
// generated include (rtl/soc/regmap.vh), so programs linked for one run
// unchanged on the other:
//   TL_BOOT_ROM_BASE  boot stub: `lui t0, %hi(boot_entry); jalr %lo(boot_entry)(t0)`, then zeros
//   TL_TIMER_BASE     TIMER page: mtime, mtimecmp, MSIP (irq_timer, irq_software)
//   TL_INTC_BASE      INTC page: no sources are wired here; a program raises
//                     irq_external through INTC.SET and ENABLE
//   TL_RAM_BASE       RAM, RAM_BYTES long
// Every other peripheral page and anything else answers with *_err (access
// fault).  Unlike tl_soc_fabric, both buses may add random wait states.  The
// testbench loads and reads the RAM through the ld_* port while rst is high.
module cpu_sim_top #(
    parameter integer RAM_BYTES = `TL_RAM_SIZE,  // a power of two
    // 0: tl_cpu; 1: tl_cpu_pipe, and both buses take a request in their own
    // ack cycle (one word per cycle; tl_cpu would see its held request twice)
    parameter integer PIPELINED = 0
) (
    input  wire        clk,
    input  wire        rst,
    input  wire [31:0] boot_entry,   // where the boot stub jumps (the ELF entry)
    input  wire        wait_states,  // 1: random wait states on both buses
    // RAM access for the testbench, only while rst is high
    input  wire        ld_we,
    /* verilator lint_off UNUSEDSIGNAL */  // the word index is used
    input  wire [31:0] ld_addr,      // byte address inside the RAM region
    /* verilator lint_on UNUSEDSIGNAL */
    input  wire [31:0] ld_wdata,
    output reg  [31:0] ld_rdata,     // registered: valid the cycle after ld_addr
    // tohost watch: the first non-zero word stored at tohost_addr
    input  wire [31:0] tohost_addr,
    output reg         tohost_hit,
    output reg  [31:0] tohost_value,
    output reg  [63:0] cycles,       // clock cycles since reset, frozen at tohost_hit
    output reg  [63:0] instret,      // retired instructions, frozen at tohost_hit
    output wire        irq_timer
);
    localparam integer RAM_WORDS = RAM_BYTES / 4;
    localparam integer AW        = $clog2(RAM_WORDS);
    localparam integer N_PAGES   = `TL_PERIPH_SIZE / 4096;
    localparam integer PAGE_BITS = $clog2(N_PAGES);
    localparam integer RQ        = `TL_BUS_REQ_WIDTH;
    localparam integer RS        = `TL_BUS_RSP_WIDTH;
    localparam integer ROM_AW    = $clog2(`TL_BOOT_ROM_SIZE);
    localparam [31:0]  ROM_MASK  = ~(`TL_BOOT_ROM_SIZE - 1);
    localparam [31:0]  RAM_MASK  = ~(RAM_BYTES - 1);
    localparam [31:0]  PER_MASK  = ~(`TL_PERIPH_SIZE - 1);
    localparam [N_PAGES-1:0] PAGE_USED = (1 << `TL_TIMER_PAGE) | (1 << `TL_INTC_PAGE);

    `CPU_BUS_MASTER_WIRES
    wire        retire;
    reg         ibus_ack, ibus_err, dbus_ack, dbus_err;
    reg  [31:0] ibus_rdata, dbus_rdata;
    wire [63:0] mtime;
    wire        irq_software, irq_external;

    generate
        if (PIPELINED != 0) begin : g_pipe
            tl_cpu_pipe #(.RESET_PC(`TL_BOOT_ROM_BASE)) u_cpu (
                `CPU_CORE_CONNECT
            );
        end else begin : g_multi
            tl_cpu #(.RESET_PC(`TL_BOOT_ROM_BASE)) u_cpu (
                `CPU_CORE_CONNECT
            );
        end
    endgenerate
    // a slave that takes a request in its ack cycle (PIPELINED) or not
    wire i_busy = PIPELINED == 0 && ibus_ack;
    wire d_busy = PIPELINED == 0 && dbus_ack;

    // Random wait states from a 16-bit LFSR (x^16 + x^14 + x^13 + x^11 + 1)
    reg [15:0] lfsr;
    always @(posedge clk) begin
        if (rst)
            lfsr <= 16'hACE1;
        else
            lfsr <= {lfsr[14:0], lfsr[15] ^ lfsr[13] ^ lfsr[12] ^ lfsr[10]};
    end
    wire istall = wait_states && lfsr[0];
    wire dstall = wait_states && lfsr[5];

    // ---- decode: the SoC's memory map ---------------------------------------------
    wire i_rom = (ibus_addr & ROM_MASK) == `TL_BOOT_ROM_BASE;
    wire i_ram = (ibus_addr & RAM_MASK) == `TL_RAM_BASE;
    wire d_ram = (dbus_addr & RAM_MASK) == `TL_RAM_BASE;
    wire d_per = (dbus_addr & PER_MASK) == `TL_PERIPH_BASE;
    wire [AW-1:0] i_word = ibus_addr[AW+1:2];
    wire [AW-1:0] d_word = dbus_addr[AW+1:2];
    wire [AW-1:0] l_word = ld_addr[AW+1:2];

    // ---- RAM: port A instruction fetch, port B data (or the loader in reset) ----
    reg [31:0] ram [0:RAM_WORDS-1];
    // Zeroed like .bss expects, and so that no simulator reads X.
    integer k;
    initial begin
        for (k = 0; k < RAM_WORDS; k = k + 1)
            ram[k] = 32'd0;
    end

    // Boot stub: lui x5, %hi(entry); jalr x0, %lo(entry)(x5)
    /* verilator lint_off UNUSEDSIGNAL */
    wire [31:0] entry_hi = boot_entry + 32'h800;  // %hi rounds for jalr's signed %lo
    /* verilator lint_on UNUSEDSIGNAL */
    wire [ROM_AW-3:0] rom_idx = ibus_addr[ROM_AW-1:2];
    wire [31:0] rom_word = rom_idx == 0 ? {entry_hi[31:12], 5'd5, 7'b0110111} :
                           rom_idx == 1 ? {boot_entry[11:0], 5'd5, 3'b000, 5'd0, 7'b1100111} :
                           32'd0;

    always @(posedge clk) begin
        ibus_ack <= 1'b0;
        if (!rst && ibus_req && !i_busy && !istall) begin
            ibus_ack   <= 1'b1;
            ibus_err   <= !(i_ram || i_rom);
            ibus_rdata <= i_rom ? rom_word : ram[i_word];
        end
    end

    // ---- the SoC's timer and interrupt controller on their pages ----------------
    wire d_go = !rst && dbus_req && !d_busy && !dstall;
    /* verilator lint_off UNUSEDSIGNAL */  // the other pages' requests go nowhere
    wire [RQ*N_PAGES-1:0] page_req;
    /* verilator lint_on UNUSEDSIGNAL */
    /* verilator lint_off UNDRIVEN */      // pages without a block here: tl_soc_pages answers for them
    /* verilator lint_off UNUSEDSIGNAL */
    wire [RS*N_PAGES-1:0] page_rsp;
    /* verilator lint_on UNUSEDSIGNAL */
    /* verilator lint_on UNDRIVEN */
    wire [RS-1:0]         per_rsp;

    tl_soc_pages #(.N_PAGES(N_PAGES), .PAGE_USED(PAGE_USED)) u_pages (
        .stb(d_go && d_per), .we(dbus_we), .be(dbus_be), .addr(dbus_addr[PAGE_BITS+11:0]),
        .wdata(dbus_wdata), .page_req(page_req), .page_rsp(page_rsp), .rsp(per_rsp)
    );

    tl_soc_timer u_timer (
        .clk(clk), .rst(rst), .mtime(mtime), .irq_timer(irq_timer), .irq_software(irq_software),
        .bus_req(page_req[`TL_TIMER_PAGE*RQ +: RQ]), .bus_rsp(page_rsp[`TL_TIMER_PAGE*RS +: RS])
    );

    tl_soc_intc u_intc (
        .clk(clk), .rst(rst), .src({`TL_INTC_ENABLE_MASK_WIDTH{1'b0}}), .irq_external(irq_external),
        .bus_req(page_req[`TL_INTC_PAGE*RQ +: RQ]), .bus_rsp(page_rsp[`TL_INTC_PAGE*RS +: RS])
    );

    // ---- data bus: RAM or a peripheral page, answered in the cycle after d_go ----
    always @(posedge clk) begin
        dbus_ack <= 1'b0;
        if (rst) begin
            if (ld_we)
                ram[l_word] <= ld_wdata;
            ld_rdata <= ram[l_word];
        end else if (d_go) begin
            dbus_ack   <= 1'b1;
            dbus_err   <= d_per ? per_rsp[`TL_BUS_RSP_ERR_LSB] : !d_ram;
            dbus_rdata <= d_per ? per_rsp[`TL_BUS_RSP_RDATA_MSB:`TL_BUS_RSP_RDATA_LSB] : ram[d_word];
            if (d_ram && dbus_we) begin
                if (dbus_be[0]) ram[d_word][7:0]   <= dbus_wdata[7:0];
                if (dbus_be[1]) ram[d_word][15:8]  <= dbus_wdata[15:8];
                if (dbus_be[2]) ram[d_word][23:16] <= dbus_wdata[23:16];
                if (dbus_be[3]) ram[d_word][31:24] <= dbus_wdata[31:24];
            end
        end
    end

    // ---- tohost watch and counters ----------------------------------------------
    // The store to tohost is accepted at one edge and retires in its ack
    // cycle or later (when it waits for its prefetch); the counters stop
    // after the cycle it retires in, so they include the store.
    reg tohost_seen;
    always @(posedge clk) begin
        if (rst) begin
            tohost_seen  <= 1'b0;
            tohost_hit   <= 1'b0;
            tohost_value <= 32'd0;
            cycles       <= 64'd0;
            instret      <= 64'd0;
        end else if (!tohost_hit) begin
            cycles  <= cycles + 64'd1;
            instret <= instret + {63'd0, retire};
            if (tohost_seen && retire)
                tohost_hit <= 1'b1;
            if (!tohost_seen && d_go && dbus_we && dbus_addr == tohost_addr && dbus_wdata != 32'd0) begin
                tohost_seen  <= 1'b1;
                tohost_value <= dbus_wdata;
            end
        end
    end
endmodule
`default_nettype wire
