-- SPDX-License-Identifier: MIT
-- tl_drive_interlock: the last gate between the SoC and the H-bridge pins.
-- VHDL twin of rtl/board/tl_drive_interlock.v (same generics, ports and
-- register names, proven equivalent by make lint); see that file for the
-- reasoning.
library ieee;
use ieee.std_logic_1164.all;
use ieee.numeric_std.all;
use work.tl_util_pkg.all;

entity tl_drive_interlock is
    generic (
        AXES              : positive := 2;
        FAULT_FILTER_CLKS : positive := 250     -- 5 us at 50 MHz
    );
    port (
        clk           : in  std_logic;
        rst           : in  std_logic;                             -- synchronous, active high
        estop         : in  std_logic;                             -- 1 = stop requested
        arm_sw        : in  std_logic;                             -- 1 = drives allowed; a rising edge arms
        fault         : in  std_logic_vector(AXES - 1 downto 0);   -- 1 = bridge reports a fault
        alive         : in  std_logic;                             -- 1 = the SoC's watchdog armed, not expired
        rpwm_in       : in  std_logic_vector(AXES - 1 downto 0);
        lpwm_in       : in  std_logic_vector(AXES - 1 downto 0);
        r_en_in       : in  std_logic_vector(AXES - 1 downto 0);
        l_en_in       : in  std_logic_vector(AXES - 1 downto 0);
        rpwm_out      : out std_logic_vector(AXES - 1 downto 0);
        lpwm_out      : out std_logic_vector(AXES - 1 downto 0);
        r_en_out      : out std_logic_vector(AXES - 1 downto 0);
        l_en_out      : out std_logic_vector(AXES - 1 downto 0);
        armed         : out std_logic;
        tripped       : out std_logic;                             -- a stop or fault since the last arming
        fault_latched : out std_logic_vector(AXES - 1 downto 0)    -- which axis faulted since the last arming
    );
end entity tl_drive_interlock;

architecture rtl of tl_drive_interlock is
    constant FILTER_BITS : positive := clog2(FAULT_FILTER_CLKS + 1);   -- >= 1: the generic is positive
    constant FILTER_MAX  : unsigned(FILTER_BITS - 1 downto 0) := to_unsigned(FAULT_FILTER_CLKS mod 2 ** FILTER_BITS, FILTER_BITS);

    signal fault_cnt : unsigned(FILTER_BITS * AXES - 1 downto 0);   -- consecutive clocks with fault, per axis
    signal fault_ok  : std_logic_vector(AXES - 1 downto 0);         -- fault present for FAULT_FILTER_CLKS clocks
    signal arm_sw_q  : std_logic;                                   -- arm_sw one clock ago
    signal alive_q   : std_logic;                                   -- alive one clock ago

    signal trip    : std_logic;
    signal lost    : std_logic;
    signal stop    : std_logic;
    signal arm_req : std_logic;
    signal armed_v : std_logic_vector(AXES - 1 downto 0);
begin
    trip    <= '1' when estop = '1' or fault_ok /= (fault_ok'range => '0') else '0';
    lost    <= alive_q and not alive;
    stop    <= trip or not alive;
    arm_req <= arm_sw and not arm_sw_q;
    armed_v <= (others => armed);

    process (clk)
    begin
        if rising_edge(clk) then
            if rst = '1' then
                fault_cnt <= (others => '0');
                fault_ok  <= (others => '0');
            else
                for i in 0 to AXES - 1 loop
                    if fault(i) = '0' then
                        fault_cnt(i * FILTER_BITS + FILTER_BITS - 1 downto i * FILTER_BITS) <= (others => '0');
                        fault_ok(i) <= '0';
                    elsif fault_cnt(i * FILTER_BITS + FILTER_BITS - 1 downto i * FILTER_BITS) = FILTER_MAX - 1 then
                        fault_ok(i) <= '1';
                    else
                        fault_cnt(i * FILTER_BITS + FILTER_BITS - 1 downto i * FILTER_BITS) <=
                            fault_cnt(i * FILTER_BITS + FILTER_BITS - 1 downto i * FILTER_BITS) + 1;
                    end if;
                end loop;
            end if;
        end if;
    end process;

    process (clk)
    begin
        if rising_edge(clk) then
            if rst = '1' then
                -- Up at reset counts as "was already up": no arming without a new edge.
                arm_sw_q      <= '1';
                alive_q       <= '0';
                armed         <= '0';
                tripped       <= '0';
                fault_latched <= (others => '0');
            else
                arm_sw_q <= arm_sw;
                alive_q  <= alive;
                if stop = '1' then
                    armed         <= '0';
                    tripped       <= tripped or trip or lost;
                    fault_latched <= fault_latched or fault_ok;
                elsif arm_sw = '0' then
                    armed <= '0';
                elsif arm_req = '1' then
                    armed         <= '1';
                    tripped       <= '0';
                    fault_latched <= (others => '0');
                end if;
            end if;
        end if;
    end process;

    process (clk)
    begin
        if rising_edge(clk) then
            if rst = '1' then
                rpwm_out <= (others => '0');
                lpwm_out <= (others => '0');
                r_en_out <= (others => '0');
                l_en_out <= (others => '0');
            else
                rpwm_out <= rpwm_in and armed_v;
                lpwm_out <= lpwm_in and armed_v;
                r_en_out <= r_en_in and armed_v;
                l_en_out <= l_en_in and armed_v;
            end if;
        end if;
    end process;
end architecture rtl;
