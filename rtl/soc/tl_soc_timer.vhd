-- SPDX-License-Identifier: MIT
-- tl_soc_timer: RISC-V machine timer (mtime, mtimecmp) and software interrupt.
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
        bus_req      : in  tl_bus_req_t;   -- from tl_soc_fabric (docs/soc.md, Bus)
        bus_rsp      : out tl_bus_rsp_t;   -- combinational; the fabric registers it
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
    signal wbits : std_logic_vector(31 downto 0);

    function merge(old, mask, bits : std_logic_vector(31 downto 0)) return std_logic_vector is
    begin
        return (old and not mask) or bits;
    end function;
begin
    idx   <= to_integer(unsigned(bus_req.idx));
    wr    <= bus_req.stb = '1' and bus_req.we = '1';
    wmask <= bus_req.wmask;
    wbits <= bus_req.wbits;

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
                    mtime_q(31 downto 0) <= unsigned(merge(std_logic_vector(mtime_q(31 downto 0)), wmask, wbits));
                elsif wr and idx = TL_TIMER_MTIME_HI_IDX then
                    mtime_q(63 downto 32) <= unsigned(merge(std_logic_vector(mtime_q(63 downto 32)), wmask, wbits));
                else
                    mtime_q <= mtime_q + 1;
                end if;
                if wr and idx = TL_TIMER_MTIMECMP_LO_IDX then
                    mtimecmp_q(31 downto 0) <= unsigned(merge(std_logic_vector(mtimecmp_q(31 downto 0)), wmask, wbits));
                end if;
                if wr and idx = TL_TIMER_MTIMECMP_HI_IDX then
                    mtimecmp_q(63 downto 32) <= unsigned(merge(std_logic_vector(mtimecmp_q(63 downto 32)), wmask, wbits));
                end if;
                if wr and idx = TL_TIMER_MSIP_IDX and wmask(TL_TIMER_MSIP_MSIP_LSB) = '1' then
                    msip_q <= wbits(TL_TIMER_MSIP_MSIP_LSB);
                end if;
            end if;
        end if;
    end process;

    mtime        <= std_logic_vector(mtime_q);
    irq_timer    <= '1' when mtime_q >= mtimecmp_q else '0';
    irq_software <= msip_q;

    -- Read decode: this block's registers only; tl_soc_fabric acknowledges.
    process (all)
    begin
        bus_rsp <= (rdata => (others => '0'), err => '0');
        if idx = TL_TIMER_MTIME_LO_IDX then
            bus_rsp.rdata <= std_logic_vector(mtime_q(31 downto 0));
        elsif idx = TL_TIMER_MTIME_HI_IDX then
            bus_rsp.rdata <= std_logic_vector(mtime_q(63 downto 32));
        elsif idx = TL_TIMER_MTIMECMP_LO_IDX then
            bus_rsp.rdata <= std_logic_vector(mtimecmp_q(31 downto 0));
        elsif idx = TL_TIMER_MTIMECMP_HI_IDX then
            bus_rsp.rdata <= std_logic_vector(mtimecmp_q(63 downto 32));
        elsif idx = TL_TIMER_MSIP_IDX then
            bus_rsp.rdata <= (0 => msip_q, others => '0');
        else
            bus_rsp.err <= '1';
        end if;
    end process;
end architecture rtl;
