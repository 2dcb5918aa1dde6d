-- SPDX-License-Identifier: MIT
-- tl_estop_gate: the bridge pins' very last stage - the emergency stop without a clock.
-- VHDL twin of rtl/board/tl_estop_gate.v (same generics and ports; proven
-- equivalent by make lint); see that file for the reasoning.
library ieee;
use ieee.std_logic_1164.all;

entity tl_estop_gate is
    generic (
        N : positive := 8
    );
    port (
        key_n     : in  std_logic;                          -- raw KEY[0] pin, 1 = released
        drive_in  : in  std_logic_vector(N - 1 downto 0);   -- registered bridge inputs
        drive_out : out std_logic_vector(N - 1 downto 0)    -- to the header pins
    );
end entity tl_estop_gate;

architecture rtl of tl_estop_gate is
begin
    drive_out <= drive_in and (drive_in'range => key_n);
end architecture rtl;
