-- SPDX-License-Identifier: MIT
-- tl_quad_decoder: 4x quadrature decoder for one optical encoder (A, B, index Z).
-- VHDL twin of rtl/motion/tl_quad_decoder.v (same generics, ports and internal
-- register names, which the equivalence proof matches); see that file and
-- docs/quad_decoder.md for the reasoning.
library ieee;
use ieee.std_logic_1164.all;
use ieee.numeric_std.all;

entity tl_quad_decoder is
    generic (
        FILTER_BITS  : positive := 4;    -- width of filter_len
        DIV_BITS     : positive := 16;   -- width of sample_div
        TS_BITS      : positive := 32;   -- timestamp width, clock cycles
        ILLEGAL_BITS : positive := 16    -- illegal-transition counter width (saturates)
    );
    port (
        clk            : in  std_logic;
        rst            : in  std_logic;  -- synchronous, active high; hold >= 3 clocks
        enc_a          : in  std_logic;  -- asynchronous encoder pins
        enc_b          : in  std_logic;
        enc_z          : in  std_logic;  -- tie low if the encoder has no index
        sample_div     : in  std_logic_vector(DIV_BITS - 1 downto 0);
        filter_len     : in  std_logic_vector(FILTER_BITS - 1 downto 0);
        pos_load       : in  std_logic;
        pos_load_val   : in  std_logic_vector(31 downto 0);
        illegal_clear  : in  std_logic;
        index_arm      : in  std_logic;
        position       : out std_logic_vector(31 downto 0);
        dir            : out std_logic;
        illegal_count  : out std_logic_vector(ILLEGAL_BITS - 1 downto 0);
        illegal_flag   : out std_logic;
        index_pos      : out std_logic_vector(31 downto 0);
        index_seen     : out std_logic;
        index_armed    : out std_logic;
        timestamp      : out std_logic_vector(TS_BITS - 1 downto 0);
        last_edge_time : out std_logic_vector(TS_BITS - 1 downto 0);
        edge_interval  : out std_logic_vector(TS_BITS - 1 downto 0);
        enc_filtered   : out std_logic_vector(2 downto 0)
    );
end entity tl_quad_decoder;

architecture rtl of tl_quad_decoder is
    signal sync_abz : std_logic_vector(2 downto 0);
    signal async_abz : std_logic_vector(2 downto 0);

    signal div_cnt : unsigned(DIV_BITS - 1 downto 0);
    signal sample  : std_logic;

    signal filt     : std_logic_vector(2 downto 0);
    signal filt_cnt : unsigned(3 * FILTER_BITS - 1 downto 0);
    signal n_eff    : unsigned(FILTER_BITS downto 0);

    signal prev    : std_logic_vector(2 downto 0);
    signal step    : std_logic;
    signal illegal : std_logic;
    signal up      : std_logic;
    signal z_rise  : std_logic;

    -- registers behind the outputs (VHDL twins of the Verilog output regs)
    signal position_r       : unsigned(31 downto 0);
    signal timestamp_r      : unsigned(TS_BITS - 1 downto 0);
    signal last_edge_time_r : unsigned(TS_BITS - 1 downto 0);
    signal illegal_count_r  : unsigned(ILLEGAL_BITS - 1 downto 0);
    signal index_armed_r    : std_logic;

    constant CNT_ZERO : unsigned(FILTER_BITS - 1 downto 0) := (others => '0');
begin
    -- synchronise (no reset: the filter loads the real levels during rst)
    async_abz <= enc_z & enc_b & enc_a;
    u_sync : entity work.tl_sync_2ff
        generic map (WIDTH => 3, RESET_VAL => 0)
        port map (clk => clk, rst => '0', async_in => async_abz, sync_out => sync_abz);

    -- sample strobe: one sample every sample_div + 1 clocks
    sample <= '1' when div_cnt = 0 else '0';

    process (clk)
    begin
        if rising_edge(clk) then
            if rst = '1' then
                div_cnt <= (others => '0');
            elsif sample = '1' then
                div_cnt <= unsigned(sample_div);
            else
                div_cnt <= div_cnt - 1;
            end if;
        end if;
    end process;

    -- glitch filter: N = max(filter_len, 1) disagreeing samples in a row change the level
    n_eff <= to_unsigned(1, FILTER_BITS + 1) when unsigned(filter_len) = 0
             else '0' & unsigned(filter_len);

    process (clk)
        variable c : unsigned(FILTER_BITS - 1 downto 0);
    begin
        if rising_edge(clk) then
            if rst = '1' then
                filt     <= sync_abz;
                filt_cnt <= (others => '0');
            elsif sample = '1' then
                for i in 0 to 2 loop
                    c := filt_cnt(i * FILTER_BITS + FILTER_BITS - 1 downto i * FILTER_BITS);
                    if sync_abz(i) = filt(i) then
                        filt_cnt(i * FILTER_BITS + FILTER_BITS - 1 downto i * FILTER_BITS) <= CNT_ZERO;
                    elsif ('0' & c) + 1 >= n_eff then
                        filt(i) <= sync_abz(i);
                        filt_cnt(i * FILTER_BITS + FILTER_BITS - 1 downto i * FILTER_BITS) <= CNT_ZERO;
                    else
                        filt_cnt(i * FILTER_BITS + FILTER_BITS - 1 downto i * FILTER_BITS) <= c + 1;
                    end if;
                end loop;
            end if;
        end if;
    end process;

    enc_filtered <= filt;

    -- 4x decode: A leading B counts up; both channels changing is illegal
    step    <= (filt(0) xor prev(0)) xor (filt(1) xor prev(1));
    illegal <= (filt(0) xor prev(0)) and (filt(1) xor prev(1));
    up      <= prev(1) xor filt(0);
    z_rise  <= filt(2) and not prev(2);

    process (clk)
    begin
        if rising_edge(clk) then
            if rst = '1' then
                prev             <= sync_abz;
                position_r       <= (others => '0');
                dir              <= '0';
                timestamp_r      <= (others => '0');
                last_edge_time_r <= (others => '0');
                edge_interval    <= (others => '0');
            else
                prev        <= filt;
                timestamp_r <= timestamp_r + 1;
                if step = '1' then
                    dir              <= up;
                    last_edge_time_r <= timestamp_r;
                    edge_interval    <= std_logic_vector(timestamp_r - last_edge_time_r);
                end if;
                if pos_load = '1' then
                    position_r <= unsigned(pos_load_val);
                elsif step = '1' then
                    if up = '1' then
                        position_r <= position_r + 1;
                    else
                        position_r <= position_r - 1;
                    end if;
                end if;
            end if;
        end if;
    end process;

    -- illegal transitions: counted (saturating) and flagged, no count made
    process (clk)
    begin
        if rising_edge(clk) then
            if rst = '1' then
                illegal_count_r <= (others => '0');
                illegal_flag    <= '0';
            elsif illegal = '1' then
                illegal_flag <= '1';
                if illegal_clear = '1' then
                    illegal_count_r <= to_unsigned(1, ILLEGAL_BITS);
                elsif illegal_count_r /= (illegal_count_r'range => '1') then
                    illegal_count_r <= illegal_count_r + 1;
                end if;
            elsif illegal_clear = '1' then
                illegal_count_r <= (others => '0');
                illegal_flag    <= '0';
            end if;
        end if;
    end process;

    -- index latch
    process (clk)
    begin
        if rising_edge(clk) then
            if rst = '1' then
                index_pos     <= (others => '0');
                index_seen    <= '0';
                index_armed_r <= '0';
            elsif index_arm = '1' then
                index_seen    <= '0';
                index_armed_r <= '1';
            elsif index_armed_r = '1' and z_rise = '1' then
                index_pos     <= std_logic_vector(position_r);
                index_seen    <= '1';
                index_armed_r <= '0';
            end if;
        end if;
    end process;

    position       <= std_logic_vector(position_r);
    timestamp      <= std_logic_vector(timestamp_r);
    last_edge_time <= std_logic_vector(last_edge_time_r);
    illegal_count  <= std_logic_vector(illegal_count_r);
    index_armed    <= index_armed_r;
end architecture rtl;
