-- SPDX-License-Identifier: MIT
-- tl_uart_tx: 8N1 transmitter with a run-time bit period (baud_div + 1 clocks).
-- VHDL twin of rtl/uart/tl_uart_tx.v (same ports and register names); see that file.
library ieee;
use ieee.std_logic_1164.all;
use ieee.numeric_std.all;

entity tl_uart_tx is
    port (
        clk      : in  std_logic;
        rst      : in  std_logic;                       -- synchronous, active high
        baud_div : in  std_logic_vector(15 downto 0);   -- clocks per bit - 1
        s_data   : in  std_logic_vector(7 downto 0);
        s_valid  : in  std_logic;
        s_ready  : out std_logic;
        cts_ok   : in  std_logic;                       -- start a new frame only when high
        txd      : out std_logic;                       -- idle high
        busy     : out std_logic
    );
end entity tl_uart_tx;

architecture rtl of tl_uart_tx is
    signal shift     : std_logic_vector(9 downto 0);   -- {stop, data, start}, LSB on the line
    signal bits_left : unsigned(3 downto 0);           -- 0 = idle
    signal clk_cnt   : unsigned(15 downto 0);          -- clocks left in the current bit
    signal busy_i    : std_logic;
begin
    busy_i  <= '0' when bits_left = 0 else '1';
    busy    <= busy_i;
    s_ready <= (not busy_i) and cts_ok;
    txd     <= shift(0);

    process (clk)
    begin
        if rising_edge(clk) then
            if rst = '1' then
                shift     <= (others => '1');
                bits_left <= (others => '0');
                clk_cnt   <= (others => '0');
            elsif busy_i = '0' then
                if s_valid = '1' and cts_ok = '1' then
                    shift     <= '1' & s_data & '0';
                    bits_left <= to_unsigned(10, 4);
                    clk_cnt   <= unsigned(baud_div);
                end if;
            elsif clk_cnt = 0 then
                shift     <= '1' & shift(9 downto 1);
                bits_left <= bits_left - 1;
                clk_cnt   <= unsigned(baud_div);
            else
                clk_cnt <= clk_cnt - 1;
            end if;
        end if;
    end process;
end architecture rtl;
