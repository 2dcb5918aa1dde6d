// SPDX-License-Identifier: MIT
`default_nettype none
// Test harness of the CPU (simulation only, not part of the SoC): the core,
// a two-port RAM, a boot ROM stub, the machine timer, a test interrupt
// device and the counters the ELF runner reports.  Uses the SoC memory map
// so that programs linked for it run unchanged on both:
//   0x0000_0000  boot ROM (4 KiB): `lui t0, %hi(boot_entry); jalr %lo(boot_entry)(t0)`
//   0x4000_0000  machine timer: mtime lo/hi +0x0/+0x4, mtimecmp lo/hi +0x8/+0xC
//   0x4000_1000  test interrupt device: bit 0 drives irq_external, bit 1 irq_software
//   0x8000_0000  RAM, RAM_BYTES long
// Anything else answers with *_err (access fault).  The testbench loads
// and reads the RAM through the ld_* port while rst is high.
module cpu_sim_top #(
    parameter RAM_BYTES = 65536
) (
    input  wire        clk,
    input  wire        rst,
    input  wire [31:0] boot_entry,   // where the boot stub jumps (the ELF entry)
    input  wire        wait_states,  // 1: random wait states on both buses
    // RAM access for the testbench, only while rst is high
    input  wire        ld_we,
    input  wire [31:0] ld_addr,      // byte address inside the RAM region
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
    localparam [31:0] RAM_BASE = 32'h8000_0000;
    localparam        RAM_WORDS = RAM_BYTES / 4;
    localparam        AW = $clog2(RAM_WORDS);

    wire        ibus_req, dbus_req, dbus_we, retire;
    wire [31:0] ibus_addr, dbus_addr, dbus_wdata;
    wire [3:0]  dbus_be;
    reg         ibus_ack, ibus_err, dbus_ack, dbus_err;
    reg  [31:0] ibus_rdata, dbus_rdata;
    reg  [63:0] mtime, mtimecmp;
    reg  [1:0]  test_irq;

    tl_cpu #(.RESET_PC(32'h0000_0000)) u_cpu (
        .clk(clk), .rst(rst),
        .ibus_req(ibus_req), .ibus_addr(ibus_addr), .ibus_ack(ibus_ack),
        .ibus_rdata(ibus_rdata), .ibus_err(ibus_err),
        .dbus_req(dbus_req), .dbus_addr(dbus_addr), .dbus_we(dbus_we), .dbus_be(dbus_be),
        .dbus_wdata(dbus_wdata), .dbus_ack(dbus_ack), .dbus_rdata(dbus_rdata), .dbus_err(dbus_err),
        .irq_timer(irq_timer), .irq_external(test_irq[0]), .irq_software(test_irq[1]),
        .mtime(mtime), .retire(retire)
    );

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

    // ---- RAM: port A instruction fetch, port B data (or the loader in reset) ----
    reg [31:0] ram [0:RAM_WORDS-1];
    // Zeroed like .bss expects, and so that no simulator reads X.
    integer k;
    initial begin
        for (k = 0; k < RAM_WORDS; k = k + 1)
            ram[k] = 32'd0;
    end
    wire [31:0] i_off = ibus_addr - RAM_BASE;
    wire [31:0] d_off = dbus_addr - RAM_BASE;
    /* verilator lint_off UNUSEDSIGNAL */
    wire [31:0] l_off = ld_addr - RAM_BASE;     // only the word index is used
    /* verilator lint_on UNUSEDSIGNAL */
    wire i_ram = ibus_addr >= RAM_BASE && i_off < RAM_BYTES;
    wire d_ram = dbus_addr >= RAM_BASE && d_off < RAM_BYTES;
    wire i_rom = ibus_addr < 32'h0000_1000;
    wire d_timer = dbus_addr[31:4] == 28'h4000_000;
    wire d_test  = dbus_addr[31:2] == 30'h1000_0400;
    wire [AW-1:0] i_word = i_off[AW+1:2];
    wire [AW-1:0] d_word = d_off[AW+1:2];
    wire [AW-1:0] l_word = l_off[AW+1:2];

    // Boot stub: lui x5, %hi(entry); jalr x0, %lo(entry)(x5)
    /* verilator lint_off UNUSEDSIGNAL */
    wire [31:0] entry_hi = boot_entry + 32'h800;  // %hi rounds for jalr's signed %lo
    /* verilator lint_on UNUSEDSIGNAL */
    wire [31:0] rom_word = ibus_addr[11:2] == 10'd0 ? {entry_hi[31:12], 5'd5, 7'b0110111} :
                           ibus_addr[11:2] == 10'd1 ? {boot_entry[11:0], 5'd5, 3'b000, 5'd0, 7'b1100111} :
                           32'd0;

    always @(posedge clk) begin
        ibus_ack <= 1'b0;
        if (!rst && ibus_req && !ibus_ack && !istall) begin
            ibus_ack   <= 1'b1;
            ibus_err   <= !(i_ram || i_rom);
            ibus_rdata <= i_rom ? rom_word : ram[i_word];
        end
    end

    wire d_go = !rst && dbus_req && !dbus_ack && !dstall;
    always @(posedge clk) begin
        dbus_ack <= 1'b0;
        if (rst) begin
            if (ld_we)
                ram[l_word] <= ld_wdata;
            ld_rdata <= ram[l_word];
        end else if (d_go) begin
            dbus_ack   <= 1'b1;
            dbus_err   <= !(d_ram || d_timer || d_test);
            dbus_rdata <= ram[d_word];
            if (d_ram && dbus_we) begin
                if (dbus_be[0]) ram[d_word][7:0]   <= dbus_wdata[7:0];
                if (dbus_be[1]) ram[d_word][15:8]  <= dbus_wdata[15:8];
                if (dbus_be[2]) ram[d_word][23:16] <= dbus_wdata[23:16];
                if (dbus_be[3]) ram[d_word][31:24] <= dbus_wdata[31:24];
            end
            if (d_timer) begin
                case (dbus_addr[3:2])
                    2'd0: dbus_rdata <= mtime[31:0];
                    2'd1: dbus_rdata <= mtime[63:32];
                    2'd2: dbus_rdata <= mtimecmp[31:0];
                    default: dbus_rdata <= mtimecmp[63:32];
                endcase
            end
            if (d_test)
                dbus_rdata <= {30'd0, test_irq};
        end
    end

    // ---- machine timer and test interrupt device --------------------------------
    assign irq_timer = mtime >= mtimecmp;
    always @(posedge clk) begin
        if (rst) begin
            mtime    <= 64'd0;
            mtimecmp <= {64{1'b1}};
            test_irq <= 2'b00;
        end else begin
            mtime <= mtime + 64'd1;
            if (d_go && dbus_we && d_timer) begin
                case (dbus_addr[3:2])
                    2'd0: mtime[31:0]     <= dbus_wdata;
                    2'd1: mtime[63:32]    <= dbus_wdata;
                    2'd2: mtimecmp[31:0]  <= dbus_wdata;
                    default: mtimecmp[63:32] <= dbus_wdata;
                endcase
            end
            if (d_go && dbus_we && d_test)
                test_irq <= dbus_wdata[1:0];
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
