-- SPDX-License-Identifier: MIT
-- tl_soc_sys: identification registers, watchdog and the safety latch.
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
        safety_event   : out std_logic;
        wdog_armed     : out std_logic;
        wdog_alive     : out std_logic
    );
end entity tl_soc_sys;

architecture rtl of tl_soc_sys is
    function bool_sl(b : boolean) return std_logic is
    begin
        if b then
            return '1';
        end if;
        return '0';
    end function;

    signal estop_v   : std_logic_vector(0 downto 0);
    signal estop_sv  : std_logic_vector(0 downto 0);
    signal estop_s   : std_logic;
    signal fault_s   : std_logic_vector(1 downto 0);

    signal wdog_load : unsigned(31 downto 0);
    signal wdog_cnt  : unsigned(31 downto 0);
    signal armed     : std_logic;
    signal expired   : std_logic;
    signal kick_a    : std_logic;
    signal scratch   : std_logic_vector(31 downto 0);
    signal latch     : std_logic_vector(3 downto 0);   -- {wdog, fault1, fault0, estop}
    signal event_q   : std_logic;

    signal idx       : natural range 0 to 1023;
    signal wr        : boolean;
    signal wmask     : std_logic_vector(31 downto 0);
    signal wbits     : std_logic_vector(31 downto 0);
    signal full      : boolean;
    signal kick_wr   : boolean;
    signal key_a     : boolean;
    signal kick_ok   : boolean;
    signal kick_bad  : boolean;
    signal arm_wr    : boolean;
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

    full      <= wmask = x"FFFFFFFF";
    kick_wr   <= wr and idx = TL_SYS_WDOG_KICK_IDX;
    key_a     <= kick_wr and full and wbits = TL_SYS_WDOG_KICK_KEY_KICK_A;
    kick_ok   <= armed = '1' and kick_wr and kick_a = '1' and full and wbits = TL_SYS_WDOG_KICK_KEY_KICK_B;
    kick_bad  <= armed = '1' and kick_wr and not key_a and not kick_ok;
    arm_wr    <= armed = '0' and wr and idx = TL_SYS_WDOG_ARM_IDX and full
                 and wbits = TL_SYS_WDOG_ARM_KEY_ARM_KEY and wdog_load /= 0;
    wdog_fire <= '1' when armed = '1' and expired = '0' and not kick_ok and (kick_bad or wdog_cnt = 1) else '0';
    cause     <= (wdog_fire or (expired and not bool_sl(kick_ok))) & fault_s & estop_s;
    clr       <= wbits(TL_SYS_SAFETY_WDOG_LSB downto TL_SYS_SAFETY_ESTOP_LSB)
                 when wr and idx = TL_SYS_SAFETY_IDX else (others => '0');

    process (clk)
    begin
        if rising_edge(clk) then
            if rst = '1' then
                wdog_load <= unsigned(TL_SYS_WDOG_LOAD_RESET);
                wdog_cnt  <= (others => '0');
                armed     <= '0';
                expired   <= '0';
                kick_a    <= '0';
                scratch   <= TL_SYS_SCRATCH_RESET;
                -- ESTOP set: no automatic restart after reset (firmware acknowledges).
                latch     <= "0001";
                event_q   <= '0';
            else
                -- A cause present in the clear cycle keeps its bit set.
                latch   <= (latch and not clr) or cause;
                event_q <= or (cause and not latch);
                if wr and idx = TL_SYS_WDOG_LOAD_IDX and armed = '0' then
                    wdog_load <= unsigned((std_logic_vector(wdog_load) and not wmask) or wbits);
                end if;
                if wr and idx = TL_SYS_SCRATCH_IDX then
                    scratch <= (scratch and not wmask) or wbits;
                end if;
                if kick_wr then
                    kick_a <= bool_sl(key_a);
                end if;
                if arm_wr then
                    armed <= '1';
                end if;
                -- Armed: counts down from WDOG_LOAD; a kick restarts it; reaching 1 (or a
                -- wrong kick) expires it, and it stays expired until the next kick.
                if arm_wr or kick_ok then
                    wdog_cnt <= wdog_load;
                    expired  <= '0';
                elsif wdog_fire = '1' then
                    wdog_cnt <= (others => '0');
                    expired  <= '1';
                elsif wdog_cnt /= 0 then
                    wdog_cnt <= wdog_cnt - 1;
                end if;
            end if;
        end if;
    end process;

    safe_i         <= (or latch) or (or cause);
    safe           <= safe_i;
    bridge_fault_s <= fault_s;
    safety_event   <= event_q;
    wdog_armed     <= armed;
    wdog_alive     <= armed and not expired;

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
            bus_rsp.rdata(TL_SYS_SAFETY_WDOG_ARMED_LSB)   <= armed;
            bus_rsp.rdata(TL_SYS_SAFETY_WDOG_EXPIRED_LSB) <= expired;
            bus_rsp.rdata(TL_SYS_SAFETY_WDOG_LSB downto TL_SYS_SAFETY_ESTOP_LSB) <= latch;
        elsif idx = TL_SYS_WDOG_LOAD_IDX then
            bus_rsp.rdata <= std_logic_vector(wdog_load);
        elsif idx = TL_SYS_SCRATCH_IDX then
            bus_rsp.rdata <= scratch;
        elsif idx /= TL_SYS_WDOG_KICK_IDX and idx /= TL_SYS_WDOG_ARM_IDX then
            bus_rsp.err <= '1';
        end if;
    end process;
end architecture rtl;
