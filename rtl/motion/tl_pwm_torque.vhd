-- SPDX-License-Identifier: MIT
-- tl_pwm_torque: the PWM torque block of the paper's PWM module (section II.C,
-- Fig. 6): dead-zone compensation (eq. 1), saturation (eq. 19/25),
-- double-buffered duty and direction, registered bridge pins with a safe
-- state within one clock of enable low or fault high.
-- VHDL twin of rtl/motion/tl_pwm_torque.v (same generics, ports and register
-- names, proven equivalent by make lint); see that file for the reasoning.
library ieee;
use ieee.std_logic_1164.all;
use ieee.numeric_std.all;

entity tl_pwm_torque is
    generic (
        PWM_BITS : positive := 10     -- duty resolution; period = 2^PWM_BITS - 1 ticks
    );
    port (
        clk            : in  std_logic;
        rst            : in  std_logic;                                -- synchronous, active high
        tick           : in  std_logic;                                -- from freq_div
        cmd            : in  std_logic_vector(PWM_BITS downto 0);      -- signed torque command
        pw0            : in  std_logic_vector(PWM_BITS - 1 downto 0);  -- dead-zone edge PW0
        pw_max         : in  std_logic_vector(PWM_BITS - 1 downto 0);  -- full-command duty PW_F
        enable         : in  std_logic;                                -- 0: safe state
        fault          : in  std_logic;                                -- 1: safe state
        brake_on_fault : in  std_logic;                                -- 1 = brake, 0 = coast
        dir_mode       : in  std_logic;                                -- 0 = IBT-2, 1 = PWM + DIR
        rpwm           : out std_logic;
        lpwm           : out std_logic;
        r_en           : out std_logic;
        l_en           : out std_logic;
        pwm_out        : out std_logic;
        dir_out        : out std_logic;
        period_start   : out std_logic;                                -- first clock of each period
        duty_applied   : out std_logic_vector(PWM_BITS - 1 downto 0);  -- duty of the current period
        dir_applied    : out std_logic;                                -- direction of the current period
        active         : out std_logic                                 -- 1: bridge driven
    );
end entity tl_pwm_torque;

architecture rtl of tl_pwm_torque is
    constant N     : positive := PWM_BITS;
    constant FULL  : unsigned(N - 1 downto 0) := (others => '1');            -- M = 2^N - 1
    constant PLAST : unsigned(N - 1 downto 0) := (0 => '0', others => '1');  -- M - 1
    constant HALF  : unsigned(2 * N - 1 downto 0) := to_unsigned(2 ** (N - 1) - 1, 2 * N);

    -- stage 1: magnitude with saturation (eq. 19/25), dead-zone edges
    signal cmd_neg : unsigned(N downto 0);
    signal cmd_abs : unsigned(N downto 0);
    signal mag     : unsigned(N - 1 downto 0);
    signal s1_mag  : unsigned(N - 1 downto 0);
    signal s1_nz   : std_logic;
    signal s1_neg  : std_logic;
    signal s1_base : unsigned(N - 1 downto 0);
    signal s1_span : unsigned(N - 1 downto 0);

    -- stage 2: product plus half a step for rounding
    signal s2_prod : unsigned(2 * N - 1 downto 0);
    signal s2_nz   : std_logic;
    signal s2_neg  : std_logic;
    signal s2_base : unsigned(N - 1 downto 0);

    -- stage 3: divide by M (exact for this range, see pwm_torque.v), add PW0 (eq. 1)
    signal q_sum     : unsigned(2 * N - 1 downto 0);
    signal q         : unsigned(N - 1 downto 0);
    signal duty_next : unsigned(N - 1 downto 0);
    signal dir_next  : std_logic;

    -- period counter, double-buffered duty/direction
    signal pcnt   : unsigned(N - 1 downto 0);
    signal duty_q : unsigned(N - 1 downto 0);
    signal dir_q  : std_logic;
    signal run_q  : std_logic;

    signal stop   : std_logic;
    signal start  : std_logic;
    signal pcnt_n : unsigned(N - 1 downto 0);
    signal duty_n : unsigned(N - 1 downto 0);
    signal dir_n  : std_logic;
    signal run_n  : std_logic;
    signal on_n   : std_logic;
begin
    cmd_neg <= unsigned(not cmd) + 1;
    cmd_abs <= cmd_neg when cmd(N) = '1' else unsigned(cmd);
    -- Only -2^N has bit N set in its magnitude: saturate it to -M.
    mag     <= FULL when cmd_abs(N) = '1' else cmd_abs(N - 1 downto 0);

    q_sum <= s2_prod + resize(s2_prod(2 * N - 1 downto N), 2 * N) + 1;
    q     <= q_sum(2 * N - 1 downto N);

    mapping : process (clk)
    begin
        if rising_edge(clk) then
            if rst = '1' then
                s1_mag    <= (others => '0');
                s1_nz     <= '0';
                s1_neg    <= '0';
                s1_base   <= (others => '0');
                s1_span   <= (others => '0');
                s2_prod   <= (others => '0');
                s2_nz     <= '0';
                s2_neg    <= '0';
                s2_base   <= (others => '0');
                duty_next <= (others => '0');
                dir_next  <= '0';
            else
                s1_mag <= mag;
                s1_nz  <= '1' when unsigned(cmd) /= 0 else '0';
                s1_neg <= cmd(N);
                if unsigned(pw0) < unsigned(pw_max) then
                    s1_base <= unsigned(pw0);
                else
                    s1_base <= unsigned(pw_max);
                end if;
                if unsigned(pw_max) > unsigned(pw0) then
                    s1_span <= unsigned(pw_max) - unsigned(pw0);
                else
                    s1_span <= (others => '0');
                end if;
                s2_prod <= s1_mag * s1_span + HALF;
                s2_nz   <= s1_nz;
                s2_neg  <= s1_neg;
                s2_base <= s1_base;
                if s2_nz = '1' then
                    duty_next <= s2_base + q;
                else
                    duty_next <= (others => '0');
                end if;
                dir_next <= s2_neg;
            end if;
        end if;
    end process;

    stop   <= (not enable) or fault;
    start  <= '1' when tick = '1' and pcnt = PLAST else '0';
    pcnt_n <= pcnt when tick = '0' else
              (others => '0') when start = '1' else
              pcnt + 1;
    duty_n <= duty_next when start = '1' else duty_q;
    dir_n  <= dir_next when start = '1' else dir_q;
    run_n  <= (not stop) and (start or run_q);
    on_n   <= '1' when pcnt_n < duty_n else '0';

    bridge : process (clk)
    begin
        if rising_edge(clk) then
            if rst = '1' then
                pcnt         <= PLAST;   -- the first tick starts a period
                duty_q       <= (others => '0');
                dir_q        <= '0';
                run_q        <= '0';
                period_start <= '0';
                rpwm         <= '0';
                lpwm         <= '0';
                r_en         <= '0';
                l_en         <= '0';
                pwm_out      <= '0';
                dir_out      <= '0';
            else
                pcnt         <= pcnt_n;
                duty_q       <= duty_n;
                dir_q        <= dir_n;
                run_q        <= run_n;
                period_start <= start;
                -- Pins show the state after this edge, so no output lags its counter.
                if run_n = '0' then
                    rpwm    <= '0';
                    lpwm    <= '0';
                    r_en    <= brake_on_fault;
                    l_en    <= brake_on_fault;
                    pwm_out <= '0';
                    dir_out <= '0';
                elsif dir_mode = '1' then
                    rpwm    <= '0';
                    lpwm    <= '0';
                    r_en    <= '1';
                    l_en    <= '1';
                    pwm_out <= on_n;
                    dir_out <= dir_n;
                else
                    rpwm    <= on_n and not dir_n;
                    lpwm    <= on_n and dir_n;
                    r_en    <= '1';
                    l_en    <= '1';
                    pwm_out <= '0';
                    dir_out <= '0';
                end if;
            end if;
        end if;
    end process;

    duty_applied <= std_logic_vector(duty_q);
    dir_applied  <= dir_q;
    active       <= run_q;
end architecture rtl;
