-- SPDX-License-Identifier: MIT
-- soc_sys: identification registers, watchdog and the safety latch.
-- VHDL twin of rtl/soc/tl_soc_sys.v (same entity, generics, ports and register
-- names; proven equivalent by make lint); see that file for the reasoning.
-- Register constants from rtl/soc/regmap_pkg.vhd (generated).
library ieee;
use ieee.std_logic_1164.all;
use ieee.numeric_std.all;

use work.tl_regmap_pkg.all;

entity tl_soc_sys is
    generic (
        BUILD_ID : std_logic_vector(31 downto 0) := x"00000000";
        CLK_HZ   : natural := TL_CLK_HZ
    );
    port (
        clk            : in  std_logic;
        rst            : in  std_logic;
        bus_req        : in  tl_bus_req_t;   -- from tl_soc_fabric (docs/soc.md, Bus)
        bus_rsp        : out tl_bus_rsp_t;   -- combinational; the fabric registers it
        estop          : in  std_logic;                       -- asynchronous, 1 = stop
        bridge_fault   : in  std_logic_vector(1 downto 0);    -- asynchronous, 1 = fault
        bridge_fault_s : out std_logic_vector(1 downto 0);
        safe           : out std_logic;
        safety_event   : out std_logic
    );
end entity tl_soc_sys;

architecture rtl of tl_soc_sys is
    signal estop_v   : std_logic_vector(0 downto 0);
    signal estop_sv  : std_logic_vector(0 downto 0);
    signal estop_s   : std_logic;
    signal fault_s   : std_logic_vector(1 downto 0);

    signal wdog_load : unsigned(31 downto 0);
    signal wdog_cnt  : unsigned(31 downto 0);
    signal scratch   : std_logic_vector(31 downto 0);
    signal latch     : std_logic_vector(3 downto 0);   -- {wdog, fault1, fault0, estop}
    signal event_q   : std_logic;

    signal idx       : natural range 0 to 1023;
    signal wr        : boolean;
    signal wmask     : std_logic_vector(31 downto 0);
    signal wbits     : std_logic_vector(31 downto 0);
    signal kick      : boolean;
    signal wdog_fire : std_logic;
    signal cause     : std_logic_vector(3 downto 0);
    signal clr       : std_logic_vector(3 downto 0);
    signal safe_i    : std_logic;
begin
    -- Reset values 1: a stop input already active at power-up latches at once.
    estop_v(0) <= estop;
    u_sync_estop : entity work.tl_sync_2ff
        generic map (WIDTH => 1, RESET_VAL => 1)
        port map (clk => clk, rst => rst, async_in => estop_v, sync_out => estop_sv);
    estop_s <= estop_sv(0);
    u_sync_fault : entity work.tl_sync_2ff
        generic map (WIDTH => 2, RESET_VAL => 0)
        port map (clk => clk, rst => rst, async_in => bridge_fault, sync_out => fault_s);

    idx   <= to_integer(unsigned(bus_req.idx));
    wr    <= bus_req.stb = '1' and bus_req.we = '1';
    wmask <= bus_req.wmask;
    wbits <= bus_req.wbits;

    kick      <= wr and (idx = TL_SYS_WDOG_KICK_IDX or idx = TL_SYS_WDOG_LOAD_IDX);
    wdog_fire <= '1' when wdog_load /= 0 and wdog_cnt = 1 and not kick else '0';
    cause     <= wdog_fire & fault_s & estop_s;
    clr       <= wbits(TL_SYS_SAFETY_WDOG_LSB downto TL_SYS_SAFETY_ESTOP_LSB)
                 when wr and idx = TL_SYS_SAFETY_IDX else (others => '0');

    process (clk)
    begin
        if rising_edge(clk) then
            if rst = '1' then
                wdog_load <= unsigned(TL_SYS_WDOG_LOAD_RESET);
                wdog_cnt  <= (others => '0');
                scratch   <= TL_SYS_SCRATCH_RESET;
                -- ESTOP set: no automatic restart after reset (firmware acknowledges).
                latch     <= "0001";
                event_q   <= '0';
            else
                -- A cause present in the clear cycle keeps its bit set.
                latch   <= (latch and not clr) or cause;
                event_q <= or (cause and not latch);
                if wr and idx = TL_SYS_WDOG_LOAD_IDX then
                    wdog_load <= unsigned((std_logic_vector(wdog_load) and not wmask) or wbits);
                end if;
                if wr and idx = TL_SYS_SCRATCH_IDX then
                    scratch <= (scratch and not wmask) or wbits;
                end if;
                -- Watchdog: counts down from WDOG_LOAD; reaching 1 fires and reloads.
                if kick then
                    if idx = TL_SYS_WDOG_LOAD_IDX then
                        wdog_cnt <= unsigned((std_logic_vector(wdog_load) and not wmask) or wbits);
                    else
                        wdog_cnt <= wdog_load;
                    end if;
                elsif wdog_load = 0 then
                    wdog_cnt <= (others => '0');
                elsif wdog_cnt <= 1 then
                    wdog_cnt <= wdog_load;
                else
                    wdog_cnt <= wdog_cnt - 1;
                end if;
            end if;
        end if;
    end process;

    safe_i         <= (or latch) or (or cause);
    safe           <= safe_i;
    bridge_fault_s <= fault_s;
    safety_event   <= event_q;

    -- Read decode: this block's registers only; tl_soc_fabric acknowledges.
    process (all)
    begin
        bus_rsp <= (rdata => (others => '0'), err => '0');
        if idx = TL_SYS_ID_IDX then
            bus_rsp.rdata <= TL_SYS_ID_RESET;
        elsif idx = TL_SYS_VERSION_IDX then
            bus_rsp.rdata <= TL_SYS_VERSION_RESET;
        elsif idx = TL_SYS_BUILD_ID_IDX then
            bus_rsp.rdata <= BUILD_ID;
        elsif idx = TL_SYS_CLK_HZ_IDX then
            bus_rsp.rdata <= std_logic_vector(to_unsigned(CLK_HZ, 32));
        elsif idx = TL_SYS_SAFETY_IDX then
            bus_rsp.rdata(TL_SYS_SAFETY_SAFE_LSB)     <= safe_i;
            bus_rsp.rdata(TL_SYS_SAFETY_ESTOP_IN_LSB) <= estop_s;
            bus_rsp.rdata(TL_SYS_SAFETY_WDOG_LSB downto TL_SYS_SAFETY_ESTOP_LSB) <= latch;
        elsif idx = TL_SYS_WDOG_LOAD_IDX then
            bus_rsp.rdata <= std_logic_vector(wdog_load);
        elsif idx = TL_SYS_SCRATCH_IDX then
            bus_rsp.rdata <= scratch;
        elsif idx /= TL_SYS_WDOG_KICK_IDX then
            bus_rsp.err <= '1';
        end if;
    end process;
end architecture rtl;
