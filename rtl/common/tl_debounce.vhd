-- SPDX-License-Identifier: MIT
-- tl_debounce: WIDTH independent debounce filters for synchronised inputs.
-- VHDL twin of rtl/common/tl_debounce.v (same generics, ports and register
-- names; proven equivalent by make lint); see that file for the reasoning.
library ieee;
use ieee.std_logic_1164.all;
use ieee.numeric_std.all;
use work.tl_util_pkg.all;

entity tl_debounce is
    generic (
        WIDTH       : positive := 1;
        STABLE_CLKS : positive := 50000;   -- 1 ms at 50 MHz
        RESET_VAL   : natural  := 0        -- bit 0 replicated into every bit
    );
    port (
        clk     : in  std_logic;
        rst     : in  std_logic;           -- synchronous, active high
        sync_in : in  std_logic_vector(WIDTH - 1 downto 0);
        q       : out std_logic_vector(WIDTH - 1 downto 0)   -- debounced
    );
end entity tl_debounce;

architecture rtl of tl_debounce is
    constant CNT_BITS : natural := clog2(STABLE_CLKS + 1);
    constant LAST     : unsigned(CNT_BITS - 1 downto 0) := to_unsigned(STABLE_CLKS - 1, CNT_BITS);

    signal out_q : std_logic_vector(WIDTH - 1 downto 0);
    signal cnt   : unsigned(CNT_BITS * WIDTH - 1 downto 0);
begin
    process (clk)
    begin
        if rising_edge(clk) then
            if rst = '1' then
                out_q <= (others => bit0(RESET_VAL));
                cnt   <= (others => '0');
            else
                for i in 0 to WIDTH - 1 loop
                    if sync_in(i) = out_q(i) then
                        cnt(i * CNT_BITS + CNT_BITS - 1 downto i * CNT_BITS) <= (others => '0');
                    elsif cnt(i * CNT_BITS + CNT_BITS - 1 downto i * CNT_BITS) = LAST then
                        out_q(i) <= sync_in(i);
                        cnt(i * CNT_BITS + CNT_BITS - 1 downto i * CNT_BITS) <= (others => '0');
                    else
                        cnt(i * CNT_BITS + CNT_BITS - 1 downto i * CNT_BITS) <=
                            cnt(i * CNT_BITS + CNT_BITS - 1 downto i * CNT_BITS) + 1;
                    end if;
                end loop;
            end if;
        end if;
    end process;

    q <= out_q;
end architecture rtl;
