-- SPDX-License-Identifier: MIT
-- tl_freq_div: the frequency generator block of the paper's PWM module
-- (section II.C, eq. 2-4, Fig. 5).
-- VHDL twin of rtl/motion/tl_freq_div.v (same generics, ports and register
-- names, proven equivalent by make lint); see that file for the reasoning.
library ieee;
use ieee.std_logic_1164.all;
use ieee.numeric_std.all;

entity tl_freq_div is
    generic (
        DIV_BITS         : positive := 16;          -- divisor register width
        DEFAULT_DIV      : positive := 109          -- divisor after reset, 1 .. 2^DIV_BITS - 1 (109: 448 Hz)
    );
    port (
        clk    : in  std_logic;
        rst    : in  std_logic;                                -- synchronous, active high
        div_we : in  std_logic;                                -- load div_in into the divisor register
        div_in : in  std_logic_vector(DIV_BITS - 1 downto 0);  -- new divisor (Count_max)
        div    : out std_logic_vector(DIV_BITS - 1 downto 0);  -- divisor register as the counter uses it
        tick   : out std_logic                                 -- one-clock pulse every max(div, 1) clocks
    );
end entity tl_freq_div;

architecture rtl of tl_freq_div is
    constant DEFAULT_DIV_VEC : unsigned(DIV_BITS - 1 downto 0) := to_unsigned(DEFAULT_DIV, DIV_BITS);

    signal div_q   : unsigned(DIV_BITS - 1 downto 0);
    signal cnt     : unsigned(DIV_BITS - 1 downto 0);   -- clocks since the last tick, 0 .. div-1
    -- One bit wider so that cnt + 1 cannot wrap when cnt is at its maximum.
    signal cnt_inc : unsigned(DIV_BITS downto 0);
    signal wrap    : std_logic;
begin
    cnt_inc <= ('0' & cnt) + 1;
    wrap    <= '1' when cnt_inc >= ('0' & div_q) else '0';

    process (clk)
    begin
        if rising_edge(clk) then
            if rst = '1' then
                div_q <= DEFAULT_DIV_VEC;
                cnt   <= (others => '0');
                tick  <= '0';
            else
                if div_we = '1' then
                    div_q <= unsigned(div_in);
                end if;
                tick <= wrap;
                if wrap = '1' then
                    cnt <= (others => '0');
                else
                    cnt <= cnt_inc(DIV_BITS - 1 downto 0);
                end if;
            end if;
        end if;
    end process;

    div <= std_logic_vector(div_q);
end architecture rtl;
