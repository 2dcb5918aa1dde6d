-- SPDX-License-Identifier: MIT
-- tl_soc_gpio: LEDR, SW, KEY and HEX0..HEX5 as registers.
-- VHDL twin of rtl/soc/tl_soc_gpio.v (same entity, ports and register names;
-- proven equivalent by make lint); see that file for the reasoning.
-- Register constants from rtl/soc/regmap_pkg.vhd (generated).
library ieee;
use ieee.std_logic_1164.all;
use ieee.numeric_std.all;

use work.tl_regmap_pkg.all;

entity tl_soc_gpio is
    port (
        clk       : in  std_logic;
        rst       : in  std_logic;
        bus_req   : in  tl_bus_req_t;   -- from tl_soc_fabric (docs/soc.md, Bus)
        bus_rsp   : out tl_bus_rsp_t;   -- combinational; the fabric registers it
        ledr      : out std_logic_vector(9 downto 0);
        sw        : in  std_logic_vector(9 downto 0);   -- asynchronous
        key_n     : in  std_logic_vector(3 downto 0);   -- asynchronous, active low
        hex0_n    : out std_logic_vector(6 downto 0);
        hex1_n    : out std_logic_vector(6 downto 0);
        hex2_n    : out std_logic_vector(6 downto 0);
        hex3_n    : out std_logic_vector(6 downto 0);
        hex4_n    : out std_logic_vector(6 downto 0);
        hex5_n    : out std_logic_vector(6 downto 0);
        key_event : out std_logic
    );
end entity tl_soc_gpio;

architecture rtl of tl_soc_gpio is
    signal sw_s        : std_logic_vector(9 downto 0);
    signal key_n_s     : std_logic_vector(3 downto 0);
    signal key         : std_logic_vector(3 downto 0);
    signal ledr_q      : std_logic_vector(9 downto 0);
    signal hex_lo_q    : std_logic_vector(31 downto 0);
    signal hex_hi_q    : std_logic_vector(31 downto 0);
    signal key_q       : std_logic_vector(3 downto 0);
    signal key_edge    : std_logic_vector(3 downto 0);
    signal key_event_q : std_logic;

    signal idx   : natural range 0 to 1023;
    signal wr    : boolean;
    signal wmask : std_logic_vector(31 downto 0);
    signal wbits : std_logic_vector(31 downto 0);
    signal press : std_logic_vector(3 downto 0);
    signal clr   : std_logic_vector(3 downto 0);
begin
    -- Idle levels as reset values: switches read 0, released keys read 1 (low active).
    u_sync_sw : entity work.tl_sync_2ff
        generic map (WIDTH => 10, RESET_VAL => 0)
        port map (clk => clk, rst => rst, async_in => sw, sync_out => sw_s);
    u_sync_key : entity work.tl_sync_2ff
        generic map (WIDTH => 4, RESET_VAL => 1)
        port map (clk => clk, rst => rst, async_in => key_n, sync_out => key_n_s);

    key   <= not key_n_s;
    idx   <= to_integer(unsigned(bus_req.idx));
    wr    <= bus_req.stb = '1' and bus_req.we = '1';
    wmask <= bus_req.wmask;
    wbits <= bus_req.wbits;
    press <= key and not key_q;
    clr   <= wbits(3 downto 0) when wr and idx = TL_GPIO_KEY_EDGE_IDX else (others => '0');

    process (clk)
    begin
        if rising_edge(clk) then
            if rst = '1' then
                ledr_q      <= TL_GPIO_LEDR_RESET(9 downto 0);
                hex_lo_q    <= TL_GPIO_HEX_LO_RESET;
                hex_hi_q    <= TL_GPIO_HEX_HI_RESET;
                key_q       <= (others => '0');
                key_edge    <= (others => '0');
                key_event_q <= '0';
            else
                key_q       <= key;
                -- A press in the same cycle as the clear wins.
                key_edge    <= (key_edge and not clr) or press;
                key_event_q <= or press;
                if wr and idx = TL_GPIO_LEDR_IDX then
                    ledr_q <= (ledr_q and not wmask(9 downto 0)) or wbits(9 downto 0);
                end if;
                if wr and idx = TL_GPIO_HEX_LO_IDX then
                    hex_lo_q <= ((hex_lo_q and not wmask) or wbits) and TL_GPIO_HEX_LO_RW_MASK;
                end if;
                if wr and idx = TL_GPIO_HEX_HI_IDX then
                    hex_hi_q <= ((hex_hi_q and not wmask) or wbits) and TL_GPIO_HEX_HI_RW_MASK;
                end if;
            end if;
        end if;
    end process;

    ledr      <= ledr_q;
    hex0_n    <= not hex_lo_q(TL_GPIO_HEX_LO_HEX0_MSB downto TL_GPIO_HEX_LO_HEX0_LSB);
    hex1_n    <= not hex_lo_q(TL_GPIO_HEX_LO_HEX1_MSB downto TL_GPIO_HEX_LO_HEX1_LSB);
    hex2_n    <= not hex_lo_q(TL_GPIO_HEX_LO_HEX2_MSB downto TL_GPIO_HEX_LO_HEX2_LSB);
    hex3_n    <= not hex_lo_q(TL_GPIO_HEX_LO_HEX3_MSB downto TL_GPIO_HEX_LO_HEX3_LSB);
    hex4_n    <= not hex_hi_q(TL_GPIO_HEX_HI_HEX4_MSB downto TL_GPIO_HEX_HI_HEX4_LSB);
    hex5_n    <= not hex_hi_q(TL_GPIO_HEX_HI_HEX5_MSB downto TL_GPIO_HEX_HI_HEX5_LSB);
    key_event <= key_event_q;

    -- Read decode: this block's registers only; tl_soc_fabric acknowledges.
    process (all)
    begin
        bus_rsp <= (rdata => (others => '0'), err => '0');
        if idx = TL_GPIO_LEDR_IDX then
            bus_rsp.rdata(9 downto 0) <= ledr_q;
        elsif idx = TL_GPIO_SW_IDX then
            bus_rsp.rdata(9 downto 0) <= sw_s;
        elsif idx = TL_GPIO_KEY_IDX then
            bus_rsp.rdata(3 downto 0) <= key;
        elsif idx = TL_GPIO_KEY_EDGE_IDX then
            bus_rsp.rdata(3 downto 0) <= key_edge;
        elsif idx = TL_GPIO_HEX_LO_IDX then
            bus_rsp.rdata <= hex_lo_q;
        elsif idx = TL_GPIO_HEX_HI_IDX then
            bus_rsp.rdata <= hex_hi_q;
        else
            bus_rsp.err <= '1';
        end if;
    end process;
end architecture rtl;
