-- SPDX-License-Identifier: MIT
-- soc_timer: RISC-V machine timer (mtime, mtimecmp) and software interrupt.
-- VHDL twin of rtl/soc/tl_soc_timer.v (same entity, ports and register names;
-- proven equivalent by make lint); see that file for the reasoning.
-- Register constants from rtl/soc/regmap_pkg.vhd (generated).
library ieee;
use ieee.std_logic_1164.all;
use ieee.numeric_std.all;

use work.tl_regmap_pkg.all;

entity tl_soc_timer is
    port (
        clk          : in  std_logic;
        rst          : in  std_logic;
        req          : in  std_logic;
        we           : in  std_logic;
        be           : in  std_logic_vector(3 downto 0);
        addr         : in  std_logic_vector(11 downto 0);
        wdata        : in  std_logic_vector(31 downto 0);
        ack          : out std_logic;
        err          : out std_logic;
        rdata        : out std_logic_vector(31 downto 0);
        mtime        : out std_logic_vector(63 downto 0);
        irq_timer    : out std_logic;
        irq_software : out std_logic
    );
end entity tl_soc_timer;

architecture rtl of tl_soc_timer is
    signal mtime_q    : unsigned(63 downto 0);
    signal mtimecmp_q : unsigned(63 downto 0);
    signal msip_q     : std_logic;

    signal idx   : natural range 0 to 1023;
    signal wr    : boolean;
    signal wmask : std_logic_vector(31 downto 0);

    function merge(old, new_val, mask : std_logic_vector(31 downto 0)) return std_logic_vector is
    begin
        return (old and not mask) or (new_val and mask);
    end function;
begin
    idx   <= to_integer(unsigned(addr(11 downto 2)));
    wr    <= req = '1' and we = '1';
    wmask <= (31 downto 24 => be(3), 23 downto 16 => be(2), 15 downto 8 => be(1), 7 downto 0 => be(0));

    process (clk)
    begin
        if rising_edge(clk) then
            if rst = '1' then
                mtime_q    <= (others => '0');
                -- Two halves: GHDL 2.0's Verilog writer prints constants wider
                -- than 32 bits as strings, which breaks the equivalence proof.
                mtimecmp_q(31 downto 0)  <= unsigned(TL_TIMER_MTIMECMP_LO_RESET);
                mtimecmp_q(63 downto 32) <= unsigned(TL_TIMER_MTIMECMP_HI_RESET);
                msip_q     <= TL_TIMER_MSIP_RESET(TL_TIMER_MSIP_MSIP_LSB);
            else
                -- A write to mtime replaces the count for this cycle (no increment).
                if wr and idx = TL_TIMER_MTIME_LO_IDX then
                    mtime_q(31 downto 0) <= unsigned(merge(std_logic_vector(mtime_q(31 downto 0)), wdata, wmask));
                elsif wr and idx = TL_TIMER_MTIME_HI_IDX then
                    mtime_q(63 downto 32) <= unsigned(merge(std_logic_vector(mtime_q(63 downto 32)), wdata, wmask));
                else
                    mtime_q <= mtime_q + 1;
                end if;
                if wr and idx = TL_TIMER_MTIMECMP_LO_IDX then
                    mtimecmp_q(31 downto 0) <= unsigned(merge(std_logic_vector(mtimecmp_q(31 downto 0)), wdata, wmask));
                end if;
                if wr and idx = TL_TIMER_MTIMECMP_HI_IDX then
                    mtimecmp_q(63 downto 32) <= unsigned(merge(std_logic_vector(mtimecmp_q(63 downto 32)), wdata, wmask));
                end if;
                if wr and idx = TL_TIMER_MSIP_IDX and be(0) = '1' then
                    msip_q <= wdata(TL_TIMER_MSIP_MSIP_LSB);
                end if;
            end if;
        end if;
    end process;

    -- Bus response: one cycle after the request strobe.
    process (clk)
    begin
        if rising_edge(clk) then
            if rst = '1' then
                ack   <= '0';
                err   <= '0';
                rdata <= (others => '0');
            else
                ack   <= req;
                err   <= '0';
                rdata <= (others => '0');
                if req = '1' then
                    if idx = TL_TIMER_MTIME_LO_IDX then
                        rdata <= std_logic_vector(mtime_q(31 downto 0));
                    elsif idx = TL_TIMER_MTIME_HI_IDX then
                        rdata <= std_logic_vector(mtime_q(63 downto 32));
                    elsif idx = TL_TIMER_MTIMECMP_LO_IDX then
                        rdata <= std_logic_vector(mtimecmp_q(31 downto 0));
                    elsif idx = TL_TIMER_MTIMECMP_HI_IDX then
                        rdata <= std_logic_vector(mtimecmp_q(63 downto 32));
                    elsif idx = TL_TIMER_MSIP_IDX then
                        rdata <= (0 => msip_q, others => '0');
                    else
                        err <= '1';
                    end if;
                end if;
            end if;
        end if;
    end process;

    mtime        <= std_logic_vector(mtime_q);
    irq_timer    <= '1' when mtime_q >= mtimecmp_q else '0';
    irq_software <= msip_q;
end architecture rtl;
