-- SPDX-License-Identifier: MIT
-- tl_soc_uart: the RN-XV WiFi link as a register page around rtl/uart/tl_uart.
-- VHDL twin of rtl/soc/tl_soc_uart.v (same entity, generics, ports and register
-- names; proven equivalent by make lint); see that file for the reasoning.
-- Register constants from rtl/soc/regmap_pkg.vhd (generated).
library ieee;
use ieee.std_logic_1164.all;
use ieee.numeric_std.all;
use ieee.math_real.all;

use work.tl_regmap_pkg.all;

entity tl_soc_uart is
    generic (
        CLK_HZ     : positive := 50_000_000;
        FIFO_DEPTH : positive := 16
    );
    port (
        clk      : in  std_logic;
        rst      : in  std_logic;
        bus_req  : in  tl_bus_req_t;   -- from tl_soc_fabric (docs/soc.md, Bus)
        bus_rsp  : out tl_bus_rsp_t;   -- combinational; the fabric registers it
        rxd      : in  std_logic;
        txd      : out std_logic;
        cts_n    : in  std_logic;
        rts_n    : out std_logic;
        rx_event : out std_logic;
        tx_event : out std_logic
    );
end entity tl_soc_uart;

architecture rtl of tl_soc_uart is
    constant LVL_BITS : positive := integer(ceil(log2(real(FIFO_DEPTH)))) + 1;

    signal baud_q      : std_logic_vector(15 downto 0);
    signal flow_q      : std_logic;
    signal err_q       : std_logic_vector(3 downto 0);   -- {tx_drop, overrun, break, frame}
    signal frame_count : unsigned(15 downto 0);

    signal rx_data       : std_logic_vector(7 downto 0);
    signal rx_valid      : std_logic;
    signal tx_ready      : std_logic;
    signal tx_busy       : std_logic;
    signal rx_level      : std_logic_vector(LVL_BITS - 1 downto 0);
    signal tx_level      : std_logic_vector(LVL_BITS - 1 downto 0);
    signal frame_error   : std_logic;
    signal break_detect  : std_logic;
    signal overrun_error : std_logic;
    signal overrun_count : std_logic_vector(15 downto 0);
    signal rts_n_i       : std_logic;

    signal idx     : natural range 0 to 1023;
    signal wr      : boolean;
    signal rd      : boolean;
    signal wmask   : std_logic_vector(15 downto 0);
    signal wbits   : std_logic_vector(15 downto 0);
    signal tx_push : std_logic;
    signal rx_pop  : std_logic;
    signal cnt_clr : boolean;
    signal err_wr  : boolean;
    signal err_set : std_logic_vector(3 downto 0);
    signal err_clr : std_logic_vector(3 downto 0);
    signal tx_idle : std_logic;
    signal ovr_clr : std_logic;
begin
    idx     <= to_integer(unsigned(bus_req.idx));
    wr      <= bus_req.stb = '1' and bus_req.we = '1';
    rd      <= bus_req.stb = '1' and bus_req.we = '0';
    wmask   <= bus_req.wmask(15 downto 0);
    wbits   <= bus_req.wbits(15 downto 0);
    tx_push <= '1' when wr and idx = TL_UART_TX_DATA_IDX and wmask(0) = '1' else '0';
    rx_pop  <= '1' when rd and idx = TL_UART_RX_DATA_IDX else '0';
    cnt_clr <= wr and idx = TL_UART_CNT_CLEAR_IDX;
    err_wr  <= wr and idx = TL_UART_ERR_IDX;
    ovr_clr <= '1' when cnt_clr and wbits(TL_UART_CNT_CLEAR_OVERRUN_LSB) = '1' else '0';

    u_uart : entity work.tl_uart
        generic map (CLK_HZ => CLK_HZ, FIFO_DEPTH => FIFO_DEPTH)
        port map (
            clk => clk, rst => rst, baud_div => baud_q, flow_en => flow_q,
            s_tx_data => wbits(7 downto 0), s_tx_valid => tx_push, s_tx_ready => tx_ready,
            m_rx_data => rx_data, m_rx_valid => rx_valid, m_rx_ready => rx_pop,
            rx_level => rx_level, tx_level => tx_level, tx_busy => tx_busy,
            frame_error => frame_error, break_detect => break_detect,
            overrun_error => overrun_error, overrun_count => overrun_count,
            overrun_clear => ovr_clr,
            rxd => rxd, txd => txd, cts_n => cts_n, rts_n => rts_n_i
        );

    err_set <= (tx_push and not tx_ready) & overrun_error & break_detect & frame_error;
    err_clr <= wbits(TL_UART_ERR_TX_DROP_LSB downto TL_UART_ERR_FRAME_LSB) when err_wr else (others => '0');

    process (clk)
    begin
        if rising_edge(clk) then
            if rst = '1' then
                baud_q      <= TL_UART_BAUD_DIV_RESET(15 downto 0);
                flow_q      <= TL_UART_CTRL_RESET(TL_UART_CTRL_FLOW_EN_LSB);
                err_q       <= (others => '0');
                frame_count <= (others => '0');
            else
                if wr and idx = TL_UART_BAUD_DIV_IDX then
                    baud_q <= (baud_q and not wmask) or wbits;
                end if;
                if wr and idx = TL_UART_CTRL_IDX and wmask(TL_UART_CTRL_FLOW_EN_LSB) = '1' then
                    flow_q <= wbits(TL_UART_CTRL_FLOW_EN_LSB);
                end if;
                -- A new error in the clearing clock stays set.
                err_q <= (err_q and not err_clr) or err_set;
                if cnt_clr and wbits(TL_UART_CNT_CLEAR_FRAME_LSB) = '1' then
                    if frame_error = '1' then
                        frame_count <= to_unsigned(1, 16);
                    else
                        frame_count <= (others => '0');
                    end if;
                elsif frame_error = '1' and frame_count /= x"FFFF" then
                    frame_count <= frame_count + 1;
                end if;
            end if;
        end if;
    end process;

    tx_idle <= '1' when tx_busy = '0' and unsigned(tx_level) = 0 else '0';

    rts_n    <= rts_n_i;
    rx_event <= rx_valid;
    tx_event <= tx_idle;

    -- Read decode: this block's registers only; tl_soc_fabric acknowledges.
    process (all)
    begin
        bus_rsp <= (rdata => (others => '0'), err => '0');
        if idx = TL_UART_RX_DATA_IDX then
            if rx_valid = '1' then
                bus_rsp.rdata(TL_UART_RX_DATA_DATA_MSB downto TL_UART_RX_DATA_DATA_LSB) <= rx_data;
            end if;
            bus_rsp.rdata(TL_UART_RX_DATA_VALID_LSB) <= rx_valid;
        elsif idx = TL_UART_STATUS_IDX then
            bus_rsp.rdata(TL_UART_STATUS_TX_READY_LSB) <= tx_ready;
            bus_rsp.rdata(TL_UART_STATUS_TX_IDLE_LSB)  <= tx_idle;
            bus_rsp.rdata(TL_UART_STATUS_RX_VALID_LSB) <= rx_valid;
            bus_rsp.rdata(TL_UART_STATUS_RTS_N_LSB)    <= rts_n_i;
            bus_rsp.rdata(TL_UART_STATUS_RX_LEVEL_LSB + LVL_BITS - 1 downto TL_UART_STATUS_RX_LEVEL_LSB) <= rx_level;
            bus_rsp.rdata(TL_UART_STATUS_TX_LEVEL_LSB + LVL_BITS - 1 downto TL_UART_STATUS_TX_LEVEL_LSB) <= tx_level;
        elsif idx = TL_UART_BAUD_DIV_IDX then
            bus_rsp.rdata(15 downto 0) <= baud_q;
        elsif idx = TL_UART_CTRL_IDX then
            bus_rsp.rdata(TL_UART_CTRL_FLOW_EN_LSB) <= flow_q;
        elsif idx = TL_UART_ERR_IDX then
            bus_rsp.rdata(3 downto 0) <= err_q;
        elsif idx = TL_UART_FRAME_COUNT_IDX then
            bus_rsp.rdata(15 downto 0) <= std_logic_vector(frame_count);
        elsif idx = TL_UART_OVERRUN_COUNT_IDX then
            bus_rsp.rdata(15 downto 0) <= overrun_count;
        elsif idx /= TL_UART_TX_DATA_IDX and idx /= TL_UART_CNT_CLEAR_IDX then
            bus_rsp.err <= '1';
        end if;
    end process;
end architecture rtl;
