-- SPDX-License-Identifier: MIT
-- tl_soc_safety_gate: forces every PWM output low in reset, while `safe`, or while
-- the raw e-stop input is high (combinationally); the enables pass.
-- VHDL twin of rtl/soc/tl_soc_safety_gate.v (proven equivalent by make lint);
-- see that file for the reasoning.
library ieee;
use ieee.std_logic_1164.all;

entity tl_soc_safety_gate is
    generic (
        N_AXES : positive := 2
    );
    port (
        rst       : in  std_logic;
        safe      : in  std_logic;
        estop_pin : in  std_logic;   -- asynchronous, 1 = stop
        rpwm_in   : in  std_logic_vector(N_AXES - 1 downto 0);
        lpwm_in   : in  std_logic_vector(N_AXES - 1 downto 0);
        pwm_in    : in  std_logic_vector(N_AXES - 1 downto 0);
        rpwm      : out std_logic_vector(N_AXES - 1 downto 0);
        lpwm      : out std_logic_vector(N_AXES - 1 downto 0);
        pwm       : out std_logic_vector(N_AXES - 1 downto 0)
    );
end entity tl_soc_safety_gate;

architecture rtl of tl_soc_safety_gate is
    signal off : std_logic;
begin
    off  <= rst or safe or estop_pin;
    rpwm <= rpwm_in and (N_AXES - 1 downto 0 => not off);
    lpwm <= lpwm_in and (N_AXES - 1 downto 0 => not off);
    pwm  <= pwm_in  and (N_AXES - 1 downto 0 => not off);
end architecture rtl;
