// SPDX-License-Identifier: MIT
// tl_soc_fabric: everything of the SoC except the CPU - the interconnect of the
// CPU's two bus masters, boot ROM, RAM and the peripheral pages - with the
// CPU's bus and interrupt signals as ports, so bus-master test benches can
// drive it exactly as the CPU does (tb/soc_fabric).  soc.v adds the CPU.
//
// Memory map (torqueloop/spec/regmap.toml, via the `TL_* macros of regmap.vh):
//   0x0000_0000 boot ROM   ibus + dbus (dbus write -> err)
//   0x4000_0000 peripherals, 4 KiB pages, dbus only
//   0x8000_0000 RAM        ibus on port B, dbus on port A (true dual port)
// Anything else, an unused page, or an unlisted register answers err.
//
// Bus protocol, per master (the CPU's contract, rtl/cpu): req + addr (+ we,
// be, wdata) held until the one-cycle ack; rdata and err valid with ack.
// This module is the one place that acknowledges: it launches a request once
// (launch = req && !ack, so a request held through its ack cycle is not
// served twice) and answers every launched request in the next cycle, from
// the memory it went to, from the addressed peripheral page, or with an
// error.  A peripheral block only decodes its own registers: it gets a
// request bundle (strobe, we, word index, write mask and bits) and returns
// its read value and "no such register" in the same cycle (bus_rsp, layout
// in regmap.vh / regmap_pkg.vhd), which is registered here.  An access takes
// two cycles (launch, ack) and the next can launch in the cycle after the
// ack; with PIPELINED = 1 (a master that never holds a request through its
// ack cycle: rtl/cpu/tl_cpu_pipe.v) the next launches in the ack cycle, one
// access per cycle per bus.  The two masters never share a memory port, so
// they never wait for each other.
// the register map's TL_* names (generated; the include guard makes a second include empty)
`include "regmap.vh"
`include "tl_cpu_bus.vh"
`include "tl_soc_board.vh"
`default_nettype none

module tl_soc_fabric #(
    parameter integer RAM_BYTES        = `TL_RAM_SIZE,
    parameter         RAM_INIT         = "",     // $readmemh image of the RAM
    parameter         ROM_INIT         = "",     // $readmemh image of the boot ROM
    parameter [31:0]  BUILD_ID         = 32'd0,
    parameter integer CLK_HZ           = `TL_CLK_HZ,
    parameter integer LIMIT_DEBOUNCE_CLKS = 50_000,  // limit switch debounce, 1 ms
    parameter integer PIPELINED        = 0           // 1: launch in the ack cycle too (see above)
) (
    input  wire        clk,
    input  wire        rst,            // synchronous, active high
    // instruction and data bus (from the CPU)
    `CPU_BUS_PORTS(input, output),
    // to the CPU
    `CPU_IRQ_PORTS(output),
    // the board (tl_soc_board.vh)
    `SOC_BOARD_PORTS
);

    localparam integer RAM_AW = $clog2(RAM_BYTES);
    localparam integer ROM_AW = $clog2(`TL_BOOT_ROM_SIZE);
    localparam [31:0]  RAM_MASK  = ~(RAM_BYTES - 1);
    localparam [31:0]  ROM_MASK  = ~(`TL_BOOT_ROM_SIZE - 1);
    localparam [31:0]  PER_MASK  = ~(`TL_PERIPH_SIZE - 1);
    localparam [31:0]  PER_BASE  = `TL_PERIPH_BASE;
    localparam [31:0]  PER_SIZE  = `TL_PERIPH_SIZE;
    localparam integer N_PAGES   = PER_SIZE / 4096;

    // Page numbers of the peripheral blocks (regmap.vh).
    localparam integer PAGE_BITS = $clog2(N_PAGES);
    localparam integer RQ        = `TL_BUS_REQ_WIDTH;
    localparam integer RS        = `TL_BUS_RSP_WIDTH;
    localparam integer         P_TIMER = `TL_TIMER_PAGE;
    localparam integer         P_INTC  = `TL_INTC_PAGE;
    localparam integer         P_GPIO  = `TL_GPIO_PAGE;
    localparam integer         P_UART  = `TL_UART_PAGE;
    localparam integer         P_AXIS0 = `TL_AXIS0_PAGE;
    localparam integer         P_AXIS1 = `TL_AXIS1_PAGE;
    localparam integer         P_SYS   = `TL_SYS_PAGE;
    localparam integer         P_FLASH = `TL_FLASH_PAGE;
    localparam [N_PAGES-1:0]   PAGE_USED = (1 << P_TIMER) | (1 << P_INTC) | (1 << P_GPIO) | (1 << P_UART)
                                         | (1 << P_AXIS0) | (1 << P_AXIS1) | (1 << P_SYS) | (1 << P_FLASH);

    // ---- instruction bus: launch once, answer in the next cycle ---------------------------
    reg  ibus_ack_q, i_ram_q, i_err_q;
    wire i_launch = ibus_req && (PIPELINED != 0 || !ibus_ack_q);
    wire i_rom    = (ibus_addr & ROM_MASK) == `TL_BOOT_ROM_BASE;
    wire i_ram    = (ibus_addr & RAM_MASK) == `TL_RAM_BASE;

    always @(posedge clk) begin
        if (rst) begin
            ibus_ack_q <= 1'b0;
            i_ram_q    <= 1'b0;
            i_err_q    <= 1'b0;
        end else begin
            ibus_ack_q <= i_launch;
            i_ram_q    <= i_launch && i_ram;
            // Fetch from the peripherals or unmapped space: access fault.
            i_err_q    <= i_launch && !i_rom && !i_ram;
        end
    end

    // ---- data bus -----------------------------------------------------------------------------
    reg  dbus_ack_q, d_ram_q, d_per_q, d_err_q;
    wire d_launch = dbus_req && (PIPELINED != 0 || !dbus_ack_q);
    wire d_rom    = (dbus_addr & ROM_MASK) == `TL_BOOT_ROM_BASE;
    wire d_ram    = (dbus_addr & RAM_MASK) == `TL_RAM_BASE;
    wire d_per    = (dbus_addr & PER_MASK) == PER_BASE;

    // The peripheral pages: a request bundle each, the addressed one's answer.
    /* verilator lint_off UNUSEDSIGNAL */  // an empty page's request goes nowhere
    wire [RQ*N_PAGES-1:0] page_req;
    /* verilator lint_on UNUSEDSIGNAL */
    /* verilator lint_off UNDRIVEN */      // an empty page has no block: tl_soc_pages answers for it
    /* verilator lint_off UNUSEDSIGNAL */
    wire [RS*N_PAGES-1:0] page_rsp;
    /* verilator lint_on UNUSEDSIGNAL */
    /* verilator lint_on UNDRIVEN */
    wire [RS-1:0]         d_rsp;          // this cycle, for the launched access

    tl_soc_pages #(.N_PAGES(N_PAGES), .PAGE_USED(PAGE_USED)) u_pages (
        .stb(d_launch && d_per), .we(dbus_we), .be(dbus_be), .addr(dbus_addr[PAGE_BITS+11:0]),
        .wdata(dbus_wdata), .page_req(page_req), .page_rsp(page_rsp), .rsp(d_rsp)
    );

    reg  [31:0]   per_rdata;

    always @(posedge clk) begin
        if (rst) begin
            dbus_ack_q <= 1'b0;
            d_ram_q    <= 1'b0;
            d_per_q    <= 1'b0;
            d_err_q    <= 1'b0;
            per_rdata  <= 32'd0;
        end else begin
            dbus_ack_q <= d_launch;
            d_ram_q    <= d_launch && d_ram;
            d_per_q    <= d_launch && d_per;
            // Unmapped space, a write to the ROM, an empty page or an unlisted register.
            d_err_q    <= d_launch && !(d_rom && !dbus_we) && !d_ram
                                   && !(d_per && !d_rsp[`TL_BUS_RSP_ERR_LSB]);
            per_rdata  <= d_rsp[`TL_BUS_RSP_RDATA_MSB:`TL_BUS_RSP_RDATA_LSB];
        end
    end

    // ---- boot ROM -----------------------------------------------------------------------------
    wire [31:0] rom_a_rdata, rom_b_rdata;

    tl_soc_rom #(.ROM_BYTES(`TL_BOOT_ROM_SIZE), .INIT_FILE(ROM_INIT)) u_rom (
        .clk(clk),
        .a_addr(dbus_addr[ROM_AW-1:0]), .a_rdata(rom_a_rdata),
        .b_addr(ibus_addr[ROM_AW-1:0]), .b_rdata(rom_b_rdata)
    );

    // ---- RAM ----------------------------------------------------------------------------------
    wire [31:0] ram_a_rdata, ram_b_rdata;

    tl_soc_ram #(.RAM_BYTES(RAM_BYTES), .INIT_FILE(RAM_INIT)) u_ram (
        .clk(clk),
        .a_we(d_launch && d_ram && dbus_we), .a_be(dbus_be), .a_addr(dbus_addr[RAM_AW-1:0]),
        .a_wdata(dbus_wdata), .a_rdata(ram_a_rdata),
        .b_addr(ibus_addr[RAM_AW-1:0]), .b_rdata(ram_b_rdata)
    );

    // ---- peripherals, one page each -----------------------------------------------------------
    tl_soc_timer u_timer (
        .clk(clk), .rst(rst),
        .bus_req(page_req[P_TIMER*RQ +: RQ]), .bus_rsp(page_rsp[P_TIMER*RS +: RS]),
        .mtime(mtime), .irq_timer(irq_timer), .irq_software(irq_software)
    );

    wire safe;
    wire safety_event;
    wire key_event;
    wire uart_rx_event, uart_tx_event;
    wire [1:0] period_event, index_event, fault_event;
    wire [1:0] bridge_fault_s;
    wire [`TL_INTC_ENABLE_MASK_WIDTH-1:0] irq_src;

    // Interrupt sources in the bit order of INTC.PENDING.
    assign irq_src[`TL_INTC_PENDING_UART_RX_LSB]    = uart_rx_event;
    assign irq_src[`TL_INTC_PENDING_UART_TX_LSB]    = uart_tx_event;
    assign irq_src[`TL_INTC_PENDING_AX0_PERIOD_LSB] = period_event[0];
    assign irq_src[`TL_INTC_PENDING_AX1_PERIOD_LSB] = period_event[1];
    assign irq_src[`TL_INTC_PENDING_AX0_INDEX_LSB]  = index_event[0];
    assign irq_src[`TL_INTC_PENDING_AX1_INDEX_LSB]  = index_event[1];
    assign irq_src[`TL_INTC_PENDING_AX0_FAULT_LSB]  = fault_event[0];
    assign irq_src[`TL_INTC_PENDING_AX1_FAULT_LSB]  = fault_event[1];
    assign irq_src[`TL_INTC_PENDING_SAFETY_LSB]     = safety_event;
    assign irq_src[`TL_INTC_PENDING_GPIO_KEY_LSB]   = key_event;

    tl_soc_intc u_intc (
        .clk(clk), .rst(rst),
        .bus_req(page_req[P_INTC*RQ +: RQ]), .bus_rsp(page_rsp[P_INTC*RS +: RS]),
        .src(irq_src), .irq_external(irq_external)
    );

    tl_soc_gpio u_gpio (
        .clk(clk), .rst(rst),
        .bus_req(page_req[P_GPIO*RQ +: RQ]), .bus_rsp(page_rsp[P_GPIO*RS +: RS]),
        .ledr(ledr), .sw(sw), .key_n(key_n),
        .hex0_n(hex0_n), .hex1_n(hex1_n), .hex2_n(hex2_n), .hex3_n(hex3_n), .hex4_n(hex4_n), .hex5_n(hex5_n),
        .key_event(key_event)
    );

    /* verilator lint_off UNUSEDSIGNAL */
    wire wdog_armed;   // readable in SYS.SAFETY; the board needs only wdog_alive
    /* verilator lint_on UNUSEDSIGNAL */
    tl_soc_sys #(.BUILD_ID(BUILD_ID), .CLK_HZ(CLK_HZ)) u_sys (
        .clk(clk), .rst(rst),
        .bus_req(page_req[P_SYS*RQ +: RQ]), .bus_rsp(page_rsp[P_SYS*RS +: RS]),
        .estop(estop), .bridge_fault(bridge_fault), .bridge_fault_s(bridge_fault_s),
        .safe(safe), .safety_event(safety_event), .wdog_armed(wdog_armed), .wdog_alive(wdog_alive)
    );

    wire [1:0] rpwm_raw, lpwm_raw, pwm_raw;

    tl_soc_axis #(.LIMIT_DEBOUNCE_CLKS(LIMIT_DEBOUNCE_CLKS)) u_axis0 (
        .clk(clk), .rst(rst),
        .bus_req(page_req[P_AXIS0*RQ +: RQ]), .bus_rsp(page_rsp[P_AXIS0*RS +: RS]),
        .safe(safe), .bridge_fault(bridge_fault_s[0]),
        .enc_a(enc_a[0]), .enc_b(enc_b[0]), .enc_z(enc_z[0]), .lim_neg(lim_neg[0]), .lim_pos(lim_pos[0]),
        .rpwm(rpwm_raw[0]), .lpwm(lpwm_raw[0]), .r_en(r_en[0]), .l_en(l_en[0]),
        .pwm_out(pwm_raw[0]), .dir_out(dir[0]),
        .period_event(period_event[0]), .index_event(index_event[0]), .fault_event(fault_event[0])
    );

    tl_soc_axis #(.LIMIT_DEBOUNCE_CLKS(LIMIT_DEBOUNCE_CLKS)) u_axis1 (
        .clk(clk), .rst(rst),
        .bus_req(page_req[P_AXIS1*RQ +: RQ]), .bus_rsp(page_rsp[P_AXIS1*RS +: RS]),
        .safe(safe), .bridge_fault(bridge_fault_s[1]),
        .enc_a(enc_a[1]), .enc_b(enc_b[1]), .enc_z(enc_z[1]), .lim_neg(lim_neg[1]), .lim_pos(lim_pos[1]),
        .rpwm(rpwm_raw[1]), .lpwm(lpwm_raw[1]), .r_en(r_en[1]), .l_en(l_en[1]),
        .pwm_out(pwm_raw[1]), .dir_out(dir[1]),
        .period_event(period_event[1]), .index_event(index_event[1]), .fault_event(fault_event[1])
    );

    tl_soc_safety_gate #(.N_AXES(2)) u_gate (
        .rst(rst), .safe(safe), .estop_pin(estop),
        .rpwm_in(rpwm_raw), .lpwm_in(lpwm_raw), .pwm_in(pwm_raw),
        .rpwm(rpwm), .lpwm(lpwm), .pwm(pwm)
    );

    tl_soc_uart #(.CLK_HZ(CLK_HZ)) u_uart (
        .clk(clk), .rst(rst),
        .bus_req(page_req[P_UART*RQ +: RQ]), .bus_rsp(page_rsp[P_UART*RS +: RS]),
        .rxd(uart_rx), .txd(uart_tx), .cts_n(uart_cts_n), .rts_n(uart_rts_n),
        .rx_event(uart_rx_event), .tx_event(uart_tx_event)
    );

    tl_soc_flash u_flash (
        .clk(clk), .rst(rst),
        .bus_req(page_req[P_FLASH*RQ +: RQ]), .bus_rsp(page_rsp[P_FLASH*RS +: RS]),
        .flash_dclk(flash_dclk), .flash_ncs(flash_ncs), .flash_mosi(flash_mosi), .flash_miso(flash_miso)
    );

    // ---- responses: rdata and err are valid with ack ------------------------------------------
    assign ibus_ack   = ibus_ack_q;
    assign ibus_err   = i_err_q;
    assign ibus_rdata = i_ram_q ? ram_b_rdata : rom_b_rdata;

    assign dbus_ack   = dbus_ack_q;
    assign dbus_err   = d_err_q;
    assign dbus_rdata = d_ram_q ? ram_a_rdata : d_per_q ? per_rdata : rom_a_rdata;

endmodule

`default_nettype wire
