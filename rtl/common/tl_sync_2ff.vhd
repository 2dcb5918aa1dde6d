-- SPDX-License-Identifier: MIT
-- tl_sync_2ff: WIDTH independent two-flop synchronisers for asynchronous inputs.
-- VHDL twin of rtl/common/tl_sync_2ff.v (same generics and ports); see that
-- file for the reasoning.  Proven equivalent by scripts/equiv.py.
library ieee;
use ieee.std_logic_1164.all;
use work.tl_util_pkg.all;

entity tl_sync_2ff is
    generic (
        WIDTH     : positive := 1;
        RESET_VAL : natural  := 0     -- bit 0 replicated into every bit
    );
    port (
        clk      : in  std_logic;
        rst      : in  std_logic;     -- synchronous, active high
        async_in : in  std_logic_vector(WIDTH - 1 downto 0);
        sync_out : out std_logic_vector(WIDTH - 1 downto 0)
    );
end entity tl_sync_2ff;

architecture rtl of tl_sync_2ff is
    constant RST_VEC : std_logic_vector(WIDTH - 1 downto 0) := (others => bit0(RESET_VAL));

    signal meta   : std_logic_vector(WIDTH - 1 downto 0);
    signal stable : std_logic_vector(WIDTH - 1 downto 0);

    attribute altera_attribute : string;
    attribute altera_attribute of meta   : signal is "-name SYNCHRONIZER_IDENTIFICATION FORCED_IF_ASYNCHRONOUS";
    attribute altera_attribute of stable : signal is "-name SYNCHRONIZER_IDENTIFICATION FORCED_IF_ASYNCHRONOUS";
begin
    process (clk)
    begin
        if rising_edge(clk) then
            if rst = '1' then
                meta   <= RST_VEC;
                stable <= RST_VEC;
            else
                meta   <= async_in;
                stable <= meta;
            end if;
        end if;
    end process;

    sync_out <= stable;
end architecture rtl;
