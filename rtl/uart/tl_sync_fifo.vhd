-- SPDX-License-Identifier: MIT
-- tl_sync_fifo: single-clock first-word-fall-through FIFO, valid/ready on both
-- sides.  VHDL twin of rtl/uart/tl_sync_fifo.v (same generics, ports and
-- register names, matched by the equivalence proof); see that file.
library ieee;
use ieee.std_logic_1164.all;
use ieee.numeric_std.all;
use ieee.math_real.all;

entity tl_sync_fifo is
    generic (
        WIDTH : positive := 8;
        DEPTH : positive := 16    -- power of two, >= 2
    );
    port (
        clk     : in  std_logic;
        rst     : in  std_logic;  -- synchronous, active high: empties the FIFO
        s_data  : in  std_logic_vector(WIDTH - 1 downto 0);
        s_valid : in  std_logic;
        s_ready : out std_logic;
        m_data  : out std_logic_vector(WIDTH - 1 downto 0);
        m_valid : out std_logic;
        m_ready : in  std_logic;
        level   : out std_logic_vector(integer(ceil(log2(real(DEPTH)))) downto 0)
    );
end entity tl_sync_fifo;

architecture rtl of tl_sync_fifo is
    constant AW : natural := integer(ceil(log2(real(DEPTH))));

    type mem_t is array (0 to DEPTH - 1) of std_logic_vector(WIDTH - 1 downto 0);
    signal mem    : mem_t;
    signal wr_ptr : unsigned(AW downto 0);
    signal rd_ptr : unsigned(AW downto 0);

    signal level_i : unsigned(AW downto 0);
    signal full    : std_logic;
    signal empty   : std_logic;
begin
    level_i <= wr_ptr - rd_ptr;
    full    <= '1' when level_i = to_unsigned(DEPTH, AW + 1) else '0';
    empty   <= '1' when wr_ptr = rd_ptr else '0';
    s_ready <= not full;
    m_valid <= not empty;
    m_data  <= mem(to_integer(rd_ptr(AW - 1 downto 0)));
    level   <= std_logic_vector(level_i);

    process (clk)
    begin
        if rising_edge(clk) then
            if s_valid = '1' and full = '0' then
                mem(to_integer(wr_ptr(AW - 1 downto 0))) <= s_data;
            end if;
        end if;
    end process;

    process (clk)
    begin
        if rising_edge(clk) then
            if rst = '1' then
                wr_ptr <= (others => '0');
                rd_ptr <= (others => '0');
            else
                if s_valid = '1' and full = '0' then
                    wr_ptr <= wr_ptr + 1;
                end if;
                if empty = '0' and m_ready = '1' then
                    rd_ptr <= rd_ptr + 1;
                end if;
            end if;
        end if;
    end process;
end architecture rtl;
