-- SPDX-License-Identifier: MIT
-- Test top: freq_div ticks driving pwm_torque (VHDL twin of pwm_chain_top.v).
library ieee;
use ieee.std_logic_1164.all;

entity pwm_chain_top is
    generic (
        CLK_HZ           : positive := 50_000_000;
        PWM_BITS         : positive := 6;
        DIV_BITS         : positive := 16;
        DEFAULT_DIV      : positive := 40
    );
    port (
        clk          : in  std_logic;
        rst          : in  std_logic;
        div_we       : in  std_logic;
        div_in       : in  std_logic_vector(DIV_BITS - 1 downto 0);
        cmd          : in  std_logic_vector(PWM_BITS downto 0);
        pw0          : in  std_logic_vector(PWM_BITS - 1 downto 0);
        pw_max       : in  std_logic_vector(PWM_BITS - 1 downto 0);
        enable       : in  std_logic;
        div          : out std_logic_vector(DIV_BITS - 1 downto 0);
        rpwm         : out std_logic;
        lpwm         : out std_logic;
        period_start : out std_logic
    );
end entity pwm_chain_top;

architecture rtl of pwm_chain_top is
    signal tick : std_logic;
begin
    u_div : entity work.tl_freq_div
        generic map (DIV_BITS => DIV_BITS, DEFAULT_DIV => DEFAULT_DIV)
        port map (clk => clk, rst => rst, div_we => div_we, div_in => div_in, div => div, tick => tick);

    u_pwm : entity work.tl_pwm_torque
        generic map (PWM_BITS => PWM_BITS)
        port map (clk => clk, rst => rst, tick => tick, cmd => cmd, pw0 => pw0, pw_max => pw_max,
                  enable => enable, fault => '0', brake_on_fault => '1', dir_mode => '0',
                  rpwm => rpwm, lpwm => lpwm, r_en => open, l_en => open, pwm_out => open,
                  dir_out => open, period_start => period_start, duty_applied => open,
                  dir_applied => open, active => open);
end architecture rtl;
