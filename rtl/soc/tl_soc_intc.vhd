-- SPDX-License-Identifier: MIT
-- tl_soc_intc: interrupt controller for the peripherals -> irq_external.
-- VHDL twin of rtl/soc/tl_soc_intc.v (same entity, ports and register names;
-- proven equivalent by make lint); see that file for the reasoning.
-- Register constants from rtl/soc/regmap_pkg.vhd (generated).
library ieee;
use ieee.std_logic_1164.all;
use ieee.numeric_std.all;

use work.tl_regmap_pkg.all;

entity tl_soc_intc is
    generic (
        N_SRC : positive := TL_INTC_ENABLE_MASK_WIDTH   -- sources, fixed by the register map
    );
    port (
        clk          : in  std_logic;
        rst          : in  std_logic;
        bus_req      : in  tl_bus_req_t;   -- from tl_soc_fabric (docs/soc.md, Bus)
        bus_rsp      : out tl_bus_rsp_t;   -- combinational; the fabric registers it
        src          : in  std_logic_vector(N_SRC - 1 downto 0);
        irq_external : out std_logic
    );
end entity tl_soc_intc;

architecture rtl of tl_soc_intc is
    signal src_q   : std_logic_vector(N_SRC - 1 downto 0);
    signal pending : std_logic_vector(N_SRC - 1 downto 0);
    signal enable  : std_logic_vector(N_SRC - 1 downto 0);

    signal idx    : natural range 0 to 1023;
    signal wr     : boolean;
    signal wmask  : std_logic_vector(N_SRC - 1 downto 0);
    signal wbits  : std_logic_vector(N_SRC - 1 downto 0);
    signal rise   : std_logic_vector(N_SRC - 1 downto 0);
    signal clr    : std_logic_vector(N_SRC - 1 downto 0);
    signal set    : std_logic_vector(N_SRC - 1 downto 0);
    signal active : std_logic_vector(N_SRC - 1 downto 0);
begin
    idx    <= to_integer(unsigned(bus_req.idx));
    wr     <= bus_req.stb = '1' and bus_req.we = '1';
    wmask  <= bus_req.wmask(N_SRC - 1 downto 0);
    wbits  <= bus_req.wbits(N_SRC - 1 downto 0);
    rise   <= src and not src_q;
    clr    <= wbits when wr and idx = TL_INTC_PENDING_IDX else (others => '0');
    set    <= wbits when wr and idx = TL_INTC_SET_IDX else (others => '0');
    active <= pending and enable;

    process (clk)
    begin
        if rising_edge(clk) then
            if rst = '1' then
                -- Levels already high at reset release count as edges: src_q = 0.
                src_q   <= (others => '0');
                pending <= TL_INTC_PENDING_RESET(N_SRC - 1 downto 0);
                enable  <= TL_INTC_ENABLE_RESET(N_SRC - 1 downto 0);
            else
                src_q   <= src;
                pending <= (pending and not clr) or rise or set;
                if wr and idx = TL_INTC_ENABLE_IDX then
                    enable <= (enable and not wmask) or wbits;
                end if;
            end if;
        end if;
    end process;

    irq_external <= or active;

    -- Read decode: this block's registers only; tl_soc_fabric acknowledges.
    process (all)
    begin
        bus_rsp <= (rdata => (others => '0'), err => '0');
        if idx = TL_INTC_PENDING_IDX then
            bus_rsp.rdata(N_SRC - 1 downto 0) <= pending;
        elsif idx = TL_INTC_ENABLE_IDX then
            bus_rsp.rdata(N_SRC - 1 downto 0) <= enable;
        elsif idx = TL_INTC_ACTIVE_IDX then
            bus_rsp.rdata(N_SRC - 1 downto 0) <= active;
        elsif idx /= TL_INTC_SET_IDX then
            bus_rsp.err <= '1';
        end if;
    end process;
end architecture rtl;
