// SPDX-License-Identifier: MIT
// soc_fabric: everything of the SoC except the CPU - the interconnect of the
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
// The interconnect launches a request once (a one-cycle strobe to the
// selected slave) and then waits for the slave's ack, so a slave never sees
// a request twice even though the master holds req through the ack cycle.
// Every slave here acks in the cycle after the strobe: an access takes two
// cycles (launch, ack), and the next can launch in the cycle after the ack.
// The two masters never share a slave port, so they never wait for each other.
`default_nettype none

module tl_soc_fabric #(
    parameter integer RAM_BYTES        = `TL_RAM_SIZE,
    parameter         RAM_INIT         = "",     // $readmemh image of the RAM
    parameter         ROM_INIT         = "",     // $readmemh image of the boot ROM
    parameter [31:0]  BUILD_ID         = 32'd0,
    parameter integer CLK_HZ           = `TL_CLK_HZ
) (
    input  wire        clk,
    input  wire        rst,            // synchronous, active high
    // instruction bus (from the CPU)
    input  wire        ibus_req,
    input  wire [31:0] ibus_addr,
    output wire        ibus_ack,
    output wire [31:0] ibus_rdata,
    output wire        ibus_err,
    // data bus (from the CPU)
    input  wire        dbus_req,
    input  wire [31:0] dbus_addr,
    input  wire        dbus_we,
    input  wire [3:0]  dbus_be,
    input  wire [31:0] dbus_wdata,
    output wire        dbus_ack,
    output wire [31:0] dbus_rdata,
    output wire        dbus_err,
    // to the CPU
    output wire [63:0] mtime,
    output wire        irq_timer,
    output wire        irq_software,
    output wire        irq_external,
    // board: DE0-CV
    output wire [9:0]  ledr,
    input  wire [9:0]  sw,
    input  wire [3:0]  key_n,
    output wire [6:0]  hex0_n,
    output wire [6:0]  hex1_n,
    output wire [6:0]  hex2_n,
    output wire [6:0]  hex3_n,
    output wire [6:0]  hex4_n,
    output wire [6:0]  hex5_n,
    // board: two IBT-2 bridges, index = axis
    output wire [1:0]  rpwm,
    output wire [1:0]  lpwm,
    output wire [1:0]  r_en,
    output wire [1:0]  l_en,
    output wire [1:0]  pwm,            // PWM+DIR mode (PWM_CTRL.DIR_MODE = 1)
    output wire [1:0]  dir,
    input  wire [1:0]  bridge_fault,   // asynchronous, 1 = fault (comparator on R_IS/L_IS); tie 0 if absent
    // board: two encoders
    input  wire [1:0]  enc_a,
    input  wire [1:0]  enc_b,
    input  wire [1:0]  enc_z,
    // board: UART to the RN-XV
    input  wire        uart_rx,
    output wire        uart_tx,
    input  wire        uart_cts_n,
    output wire        uart_rts_n,
    // board: e-stop
    input  wire        estop           // asynchronous, 1 = stop
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
    localparam [PAGE_BITS-1:0] P_TIMER = `TL_TIMER_PAGE;
    localparam [PAGE_BITS-1:0] P_INTC  = `TL_INTC_PAGE;
    localparam [PAGE_BITS-1:0] P_GPIO  = `TL_GPIO_PAGE;
    localparam [PAGE_BITS-1:0] P_UART  = `TL_UART_PAGE;
    localparam [PAGE_BITS-1:0] P_AXIS0 = `TL_AXIS0_PAGE;
    localparam [PAGE_BITS-1:0] P_AXIS1 = `TL_AXIS1_PAGE;
    localparam [PAGE_BITS-1:0] P_SYS   = `TL_SYS_PAGE;

    // ---- instruction bus: launch once, decode ----------------------------------------------
    reg  i_busy;
    wire i_launch = ibus_req && !i_busy;
    wire i_rom    = (ibus_addr & ROM_MASK) == `TL_BOOT_ROM_BASE;
    wire i_ram    = (ibus_addr & RAM_MASK) == `TL_RAM_BASE;
    reg  i_miss_ack;

    always @(posedge clk) begin
        if (rst) begin
            i_busy     <= 1'b0;
            i_miss_ack <= 1'b0;
        end else begin
            if (i_launch)
                i_busy <= 1'b1;
            else if (ibus_ack)
                i_busy <= 1'b0;
            // Fetch from the peripherals or unmapped space: access fault.
            i_miss_ack <= i_launch && !i_rom && !i_ram;
        end
    end

    // ---- data bus -----------------------------------------------------------------------------
    reg  d_busy;
    wire d_launch = dbus_req && !d_busy;
    wire d_rom    = (dbus_addr & ROM_MASK) == `TL_BOOT_ROM_BASE;
    wire d_ram    = (dbus_addr & RAM_MASK) == `TL_RAM_BASE;
    wire d_per    = (dbus_addr & PER_MASK) == PER_BASE;
    wire [PAGE_BITS-1:0] d_page = dbus_addr[12 +: PAGE_BITS];
    wire d_page_used = (d_page == P_TIMER) || (d_page == P_INTC) || (d_page == P_GPIO) || (d_page == P_UART)
                    || (d_page == P_AXIS0) || (d_page == P_AXIS1) || (d_page == P_SYS);
    reg  d_miss_ack;

    wire d_per_launch = d_launch && d_per;
    wire req_timer = d_per_launch && (d_page == P_TIMER);
    wire req_intc  = d_per_launch && (d_page == P_INTC);
    wire req_gpio  = d_per_launch && (d_page == P_GPIO);
    wire req_uart  = d_per_launch && (d_page == P_UART);
    wire req_axis0 = d_per_launch && (d_page == P_AXIS0);
    wire req_axis1 = d_per_launch && (d_page == P_AXIS1);
    wire req_sys   = d_per_launch && (d_page == P_SYS);

    always @(posedge clk) begin
        if (rst) begin
            d_busy     <= 1'b0;
            d_miss_ack <= 1'b0;
        end else begin
            if (d_launch)
                d_busy <= 1'b1;
            else if (dbus_ack)
                d_busy <= 1'b0;
            d_miss_ack <= d_launch && !d_rom && !d_ram && !(d_per && d_page_used);
        end
    end

    // ---- boot ROM -----------------------------------------------------------------------------
    wire        rom_a_ack, rom_a_err, rom_b_ack;
    wire [31:0] rom_a_rdata, rom_b_rdata;

    tl_soc_rom #(.ROM_BYTES(`TL_BOOT_ROM_SIZE), .INIT_FILE(ROM_INIT)) u_rom (
        .clk(clk), .rst(rst),
        .a_req(d_launch && d_rom), .a_we(dbus_we), .a_addr(dbus_addr[ROM_AW-1:0]),
        .a_ack(rom_a_ack), .a_err(rom_a_err), .a_rdata(rom_a_rdata),
        .b_req(i_launch && i_rom), .b_addr(ibus_addr[ROM_AW-1:0]),
        .b_ack(rom_b_ack), .b_rdata(rom_b_rdata)
    );

    // ---- RAM ----------------------------------------------------------------------------------
    wire        ram_a_ack, ram_b_ack;
    wire [31:0] ram_a_rdata, ram_b_rdata;

    tl_soc_ram #(.RAM_BYTES(RAM_BYTES), .INIT_FILE(RAM_INIT)) u_ram (
        .clk(clk), .rst(rst),
        .a_req(d_launch && d_ram), .a_we(dbus_we), .a_be(dbus_be), .a_addr(dbus_addr[RAM_AW-1:0]),
        .a_wdata(dbus_wdata), .a_ack(ram_a_ack), .a_rdata(ram_a_rdata),
        .b_req(i_launch && i_ram), .b_addr(ibus_addr[RAM_AW-1:0]),
        .b_ack(ram_b_ack), .b_rdata(ram_b_rdata)
    );

    // ---- peripherals --------------------------------------------------------------------------
    wire [11:0] p_addr = dbus_addr[11:0];
    wire        tim_ack, tim_err, int_ack, int_err, gpio_ack, gpio_err, sys_ack, sys_err;
    wire        ax0_ack, ax0_err, ax1_ack, ax1_err, uart_ack, uart_err;
    wire [31:0] tim_rdata, int_rdata, gpio_rdata, sys_rdata, ax0_rdata, ax1_rdata, uart_rdata;

    tl_soc_timer u_timer (
        .clk(clk), .rst(rst), .req(req_timer), .we(dbus_we), .be(dbus_be), .addr(p_addr),
        .wdata(dbus_wdata), .ack(tim_ack), .err(tim_err), .rdata(tim_rdata),
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
        .clk(clk), .rst(rst), .req(req_intc), .we(dbus_we), .be(dbus_be), .addr(p_addr),
        .wdata(dbus_wdata), .ack(int_ack), .err(int_err), .rdata(int_rdata),
        .src(irq_src), .irq_external(irq_external)
    );

    tl_soc_gpio u_gpio (
        .clk(clk), .rst(rst), .req(req_gpio), .we(dbus_we), .be(dbus_be), .addr(p_addr),
        .wdata(dbus_wdata), .ack(gpio_ack), .err(gpio_err), .rdata(gpio_rdata),
        .ledr(ledr), .sw(sw), .key_n(key_n),
        .hex0_n(hex0_n), .hex1_n(hex1_n), .hex2_n(hex2_n), .hex3_n(hex3_n), .hex4_n(hex4_n), .hex5_n(hex5_n),
        .key_event(key_event)
    );

    tl_soc_sys #(.BUILD_ID(BUILD_ID), .CLK_HZ(CLK_HZ)) u_sys (
        .clk(clk), .rst(rst), .req(req_sys), .we(dbus_we), .be(dbus_be), .addr(p_addr),
        .wdata(dbus_wdata), .ack(sys_ack), .err(sys_err), .rdata(sys_rdata),
        .estop(estop), .bridge_fault(bridge_fault), .bridge_fault_s(bridge_fault_s),
        .safe(safe), .safety_event(safety_event)
    );

    wire [1:0] rpwm_raw, lpwm_raw, pwm_raw;

    tl_soc_axis u_axis0 (
        .clk(clk), .rst(rst), .req(req_axis0), .we(dbus_we), .be(dbus_be), .addr(p_addr),
        .wdata(dbus_wdata), .ack(ax0_ack), .err(ax0_err), .rdata(ax0_rdata),
        .safe(safe), .bridge_fault(bridge_fault_s[0]),
        .enc_a(enc_a[0]), .enc_b(enc_b[0]), .enc_z(enc_z[0]),
        .rpwm(rpwm_raw[0]), .lpwm(lpwm_raw[0]), .r_en(r_en[0]), .l_en(l_en[0]),
        .pwm_out(pwm_raw[0]), .dir_out(dir[0]),
        .period_event(period_event[0]), .index_event(index_event[0]), .fault_event(fault_event[0])
    );

    tl_soc_axis u_axis1 (
        .clk(clk), .rst(rst), .req(req_axis1), .we(dbus_we), .be(dbus_be), .addr(p_addr),
        .wdata(dbus_wdata), .ack(ax1_ack), .err(ax1_err), .rdata(ax1_rdata),
        .safe(safe), .bridge_fault(bridge_fault_s[1]),
        .enc_a(enc_a[1]), .enc_b(enc_b[1]), .enc_z(enc_z[1]),
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
        .clk(clk), .rst(rst), .req(req_uart), .we(dbus_we), .be(dbus_be), .addr(p_addr),
        .wdata(dbus_wdata), .ack(uart_ack), .err(uart_err), .rdata(uart_rdata),
        .rxd(uart_rx), .txd(uart_tx), .cts_n(uart_cts_n), .rts_n(uart_rts_n),
        .rx_event(uart_rx_event), .tx_event(uart_tx_event)
    );

    // ---- responses: only the addressed slave acks; rdata gated by its ack ---------------------
    assign ibus_ack   = rom_b_ack | ram_b_ack | i_miss_ack;
    assign ibus_err   = i_miss_ack;
    assign ibus_rdata = ({32{rom_b_ack}} & rom_b_rdata) | ({32{ram_b_ack}} & ram_b_rdata);

    assign dbus_ack   = rom_a_ack | ram_a_ack | tim_ack | int_ack | gpio_ack | sys_ack
                      | ax0_ack | ax1_ack | uart_ack | d_miss_ack;
    assign dbus_err   = rom_a_err | tim_err | int_err | gpio_err | sys_err | ax0_err | ax1_err
                      | uart_err | d_miss_ack;
    assign dbus_rdata = ({32{rom_a_ack}} & rom_a_rdata) | ({32{ram_a_ack}} & ram_a_rdata)
                      | ({32{tim_ack}}   & tim_rdata)   | ({32{int_ack}}   & int_rdata)
                      | ({32{gpio_ack}}  & gpio_rdata)  | ({32{sys_ack}}   & sys_rdata)
                      | ({32{ax0_ack}}   & ax0_rdata)   | ({32{ax1_ack}}   & ax1_rdata)
                      | ({32{uart_ack}}  & uart_rdata);

endmodule

`default_nettype wire
