-- SPDX-License-Identifier: MIT
-- tl_reset_sync: asynchronous assertion, synchronous release of reset.
-- VHDL twin of rtl/common/tl_reset_sync.v; see that file for the reasoning.
library ieee;
use ieee.std_logic_1164.all;

entity tl_reset_sync is
    generic (
        STAGES : positive := 2        -- >= 2
    );
    port (
        clk     : in  std_logic;
        arst_n  : in  std_logic;      -- asynchronous, active low
        rst_out : out std_logic       -- synchronous release, active high
    );
end entity tl_reset_sync;

architecture rtl of tl_reset_sync is
    -- Power up in reset; see reset_sync.v.
    signal chain : std_logic_vector(STAGES - 1 downto 0) := (others => '1');

    attribute altera_attribute : string;
    attribute altera_attribute of chain : signal is "-name SYNCHRONIZER_IDENTIFICATION FORCED_IF_ASYNCHRONOUS";
begin
    process (clk, arst_n)
    begin
        if arst_n = '0' then
            chain <= (others => '1');
        elsif rising_edge(clk) then
            chain <= chain(STAGES - 2 downto 0) & '0';
        end if;
    end process;

    rst_out <= chain(STAGES - 1);
end architecture rtl;
