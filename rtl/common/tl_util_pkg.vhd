-- SPDX-License-Identifier: MIT
-- tl_util_pkg: the helpers the VHDL twins share, written once: what their
-- Verilog twins get from $clog2 and from a RESET_VAL parameter's bit 0.
library ieee;
use ieee.std_logic_1164.all;

package tl_util_pkg is
    -- ceil(log2(n)), as Verilog's $clog2 (0 for n <= 1)
    function clog2(n : natural) return natural;
    -- bit 0 of n as a level (a RESET_VAL generic replicates it into every bit)
    function bit0(n : natural) return std_logic;
end package tl_util_pkg;

package body tl_util_pkg is
    function clog2(n : natural) return natural is
        variable r : natural := 0;
    begin
        while 2 ** r < n loop
            r := r + 1;
        end loop;
        return r;
    end function;

    function bit0(n : natural) return std_logic is
    begin
        if n mod 2 = 1 then
            return '1';
        end if;
        return '0';
    end function;
end package body tl_util_pkg;
