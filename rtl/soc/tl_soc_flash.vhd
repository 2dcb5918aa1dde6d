-- SPDX-License-Identifier: MIT
-- soc_flash: the configuration flash's serial port (SPI mode 0, one byte at a time).
-- VHDL twin of rtl/soc/tl_soc_flash.v (same entity, generic, ports and register
-- names; proven equivalent by make lint); see that file for the reasoning.
-- Register constants from rtl/soc/regmap_pkg.vhd (generated).
library ieee;
use ieee.std_logic_1164.all;
use ieee.numeric_std.all;

use work.tl_regmap_pkg.all;

entity tl_soc_flash is
    generic (
        HALF_CLKS : integer := 2            -- clocks per DCLK half period
    );
    port (
        clk        : in  std_logic;
        rst        : in  std_logic;
        flash_dclk : out std_logic;
        flash_ncs  : out std_logic;         -- active low
        flash_mosi : out std_logic;         -- to the flash (ASDO)
        flash_miso : in  std_logic;         -- from the flash (DATA0)
        bus_req    : in  tl_bus_req_t;      -- from tl_soc_fabric (docs/soc.md, Bus)
        bus_rsp    : out tl_bus_rsp_t       -- combinational; the fabric registers it
    );
end entity tl_soc_flash;

architecture rtl of tl_soc_flash is
    signal cs_q   : std_logic;
    signal busy   : std_logic;
    signal dclk_q : std_logic;
    signal div    : natural range 0 to HALF_CLKS - 1;
    signal bits   : unsigned(2 downto 0);
    signal tx_sh  : std_logic_vector(7 downto 0);
    signal rx_sh  : std_logic_vector(7 downto 0);
    signal rx_q   : std_logic_vector(7 downto 0);

    signal idx   : natural range 0 to 1023;
    signal wr    : boolean;
    signal start : boolean;
    signal tick  : boolean;
begin
    idx   <= to_integer(unsigned(bus_req.idx));
    wr    <= bus_req.stb = '1' and bus_req.we = '1';
    start <= wr and idx = TL_FLASH_TX_IDX and bus_req.wmask(0) = '1' and busy = '0';
    tick  <= busy = '1' and div = HALF_CLKS - 1;

    process (clk)
    begin
        if rising_edge(clk) then
            if rst = '1' then
                cs_q   <= '0';
                busy   <= '0';
                dclk_q <= '0';
                div    <= 0;
                bits   <= (others => '0');
                tx_sh  <= (others => '0');
                rx_sh  <= (others => '0');
                rx_q   <= (others => '0');
            else
                if wr and idx = TL_FLASH_CTRL_IDX and bus_req.wmask(0) = '1' then
                    cs_q <= bus_req.wbits(TL_FLASH_CTRL_CS_LSB);
                end if;
                if start then
                    busy  <= '1';
                    div   <= 0;
                    bits  <= "111";
                    tx_sh <= bus_req.wbits(7 downto 0);
                elsif busy = '1' then
                    if tick then
                        div <= 0;
                    else
                        div <= div + 1;
                    end if;
                    if tick and dclk_q = '0' then
                        dclk_q <= '1';                          -- rising: both sides sample
                        rx_sh  <= rx_sh(6 downto 0) & flash_miso;
                    elsif tick then
                        dclk_q <= '0';                          -- falling: the next bit goes out
                        tx_sh  <= tx_sh(6 downto 0) & '0';
                        bits   <= bits - 1;
                        if bits = 0 then
                            busy <= '0';
                            rx_q <= rx_sh;
                        end if;
                    end if;
                end if;
            end if;
        end if;
    end process;

    -- Read decode: this block's registers only; tl_soc_fabric acknowledges.
    process (all)
    begin
        bus_rsp <= (rdata => (others => '0'), err => '0');
        if idx = TL_FLASH_CTRL_IDX then
            bus_rsp.rdata(TL_FLASH_CTRL_CS_LSB) <= cs_q;
        elsif idx = TL_FLASH_TX_IDX then
            null;
        elsif idx = TL_FLASH_RX_IDX then
            bus_rsp.rdata(TL_FLASH_RX_DATA_MSB downto TL_FLASH_RX_DATA_LSB) <= rx_q;
            bus_rsp.rdata(TL_FLASH_RX_BUSY_LSB) <= busy;
        else
            bus_rsp.err <= '1';
        end if;
    end process;

    flash_dclk <= dclk_q;
    flash_ncs  <= not cs_q;
    flash_mosi <= tx_sh(7);
end architecture rtl;
