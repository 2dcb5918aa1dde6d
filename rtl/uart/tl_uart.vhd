-- SPDX-License-Identifier: MIT
-- tl_uart: the RN-XV link - 8N1 receiver and transmitter with FIFOs, run-time
-- baud divisor, overrun counting and optional RTS/CTS flow control.
-- VHDL twin of rtl/uart/tl_uart.v (same generics, ports, instance and register
-- names, matched by the equivalence proof); see that file and docs/uart.md.
library ieee;
use ieee.std_logic_1164.all;
use ieee.numeric_std.all;
use ieee.math_real.all;

entity tl_uart is
    generic (
        CLK_HZ       : positive := 50_000_000;
        DEFAULT_BAUD : positive := 115_200;
        FIFO_DEPTH   : positive := 16;   -- each FIFO, power of two >= 2
        RTS_SLACK    : positive := 4     -- free RX entries left when rts_n rises
    );
    port (
        clk           : in  std_logic;
        rst           : in  std_logic;
        baud_div      : in  std_logic_vector(15 downto 0);   -- clocks per bit - 1; 0 = DEFAULT_BAUD
        flow_en       : in  std_logic;
        s_tx_data     : in  std_logic_vector(7 downto 0);
        s_tx_valid    : in  std_logic;
        s_tx_ready    : out std_logic;
        m_rx_data     : out std_logic_vector(7 downto 0);
        m_rx_valid    : out std_logic;
        m_rx_ready    : in  std_logic;
        rx_level      : out std_logic_vector(integer(ceil(log2(real(FIFO_DEPTH)))) downto 0);
        tx_level      : out std_logic_vector(integer(ceil(log2(real(FIFO_DEPTH)))) downto 0);
        tx_busy       : out std_logic;
        frame_error   : out std_logic;
        break_detect  : out std_logic;
        overrun_error : out std_logic;
        overrun_count : out std_logic_vector(15 downto 0);
        overrun_clear : in  std_logic;
        rxd           : in  std_logic;   -- asynchronous
        txd           : out std_logic;
        cts_n         : in  std_logic;   -- asynchronous, low = peer ready
        rts_n         : out std_logic    -- low = we can take more
    );
end entity tl_uart;

architecture rtl of tl_uart is
    constant LW          : positive := integer(ceil(log2(real(FIFO_DEPTH)))) + 1;
    constant DEFAULT_DIV : natural  := (CLK_HZ + DEFAULT_BAUD / 2) / DEFAULT_BAUD - 1;
    constant MIN_DIV     : unsigned(15 downto 0) := to_unsigned(15, 16);
    constant RTS_LEVEL   : unsigned(LW - 1 downto 0) := to_unsigned(FIFO_DEPTH - RTS_SLACK, LW);

    signal div           : std_logic_vector(15 downto 0);

    signal rx_data       : std_logic_vector(7 downto 0);
    signal rx_valid      : std_logic;
    signal rx_fifo_ready : std_logic;
    signal rx_level_i    : std_logic_vector(LW - 1 downto 0);
    signal overrun       : std_logic;
    signal overrun_count_r : unsigned(15 downto 0);

    signal cts_n_v       : std_logic_vector(0 downto 0);
    signal cts_n_sync_v  : std_logic_vector(0 downto 0);
    signal tx_data       : std_logic_vector(7 downto 0);
    signal tx_valid      : std_logic;
    signal tx_ready      : std_logic;
    signal cts_ok        : std_logic;
begin
    div <= std_logic_vector(to_unsigned(DEFAULT_DIV, 16)) when unsigned(baud_div) = 0 else
           std_logic_vector(MIN_DIV) when unsigned(baud_div) < MIN_DIV else
           baud_div;

    -- receive
    u_rx : entity work.tl_uart_rx
        port map (clk => clk, rst => rst, baud_div => div, rxd => rxd,
                  m_data => rx_data, m_valid => rx_valid,
                  frame_error => frame_error, break_detect => break_detect);

    u_rx_fifo : entity work.tl_sync_fifo
        generic map (WIDTH => 8, DEPTH => FIFO_DEPTH)
        port map (clk => clk, rst => rst,
                  s_data => rx_data, s_valid => rx_valid, s_ready => rx_fifo_ready,
                  m_data => m_rx_data, m_valid => m_rx_valid, m_ready => m_rx_ready,
                  level => rx_level_i);
    rx_level <= rx_level_i;

    overrun <= rx_valid and not rx_fifo_ready;

    process (clk)
    begin
        if rising_edge(clk) then
            if rst = '1' then
                overrun_error   <= '0';
                overrun_count_r <= (others => '0');
                rts_n           <= '0';
            else
                overrun_error <= overrun;
                if overrun = '1' then
                    if overrun_clear = '1' then
                        overrun_count_r <= to_unsigned(1, 16);
                    elsif overrun_count_r /= x"ffff" then
                        overrun_count_r <= overrun_count_r + 1;
                    end if;
                elsif overrun_clear = '1' then
                    overrun_count_r <= (others => '0');
                end if;
                if flow_en = '1' and unsigned(rx_level_i) >= RTS_LEVEL then
                    rts_n <= '1';
                else
                    rts_n <= '0';
                end if;
            end if;
        end if;
    end process;
    overrun_count <= std_logic_vector(overrun_count_r);

    -- transmit
    cts_n_v(0) <= cts_n;
    u_cts_sync : entity work.tl_sync_2ff
        generic map (WIDTH => 1, RESET_VAL => 1)
        port map (clk => clk, rst => rst, async_in => cts_n_v, sync_out => cts_n_sync_v);

    u_tx_fifo : entity work.tl_sync_fifo
        generic map (WIDTH => 8, DEPTH => FIFO_DEPTH)
        port map (clk => clk, rst => rst,
                  s_data => s_tx_data, s_valid => s_tx_valid, s_ready => s_tx_ready,
                  m_data => tx_data, m_valid => tx_valid, m_ready => tx_ready,
                  level => tx_level);

    cts_ok <= (not flow_en) or (not cts_n_sync_v(0));

    u_tx : entity work.tl_uart_tx
        port map (clk => clk, rst => rst, baud_div => div,
                  s_data => tx_data, s_valid => tx_valid, s_ready => tx_ready,
                  cts_ok => cts_ok, txd => txd, busy => tx_busy);
end architecture rtl;
