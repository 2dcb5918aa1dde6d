-- SPDX-License-Identifier: MIT
-- tl_uart_rx: 8N1 receiver, run-time bit period, three-sample majority vote,
-- framing-error and break detection.  VHDL twin of rtl/uart/tl_uart_rx.v (same
-- ports and register names, matched by the equivalence proof); see that file.
library ieee;
use ieee.std_logic_1164.all;
use ieee.numeric_std.all;

entity tl_uart_rx is
    port (
        clk          : in  std_logic;
        rst          : in  std_logic;                      -- synchronous, active high
        baud_div     : in  std_logic_vector(15 downto 0);  -- clocks per bit - 1, >= 15
        rxd          : in  std_logic;                      -- asynchronous, idle high
        m_data       : out std_logic_vector(7 downto 0);
        m_valid      : out std_logic;
        frame_error  : out std_logic;
        break_detect : out std_logic
    );
end entity tl_uart_rx;

architecture rtl of tl_uart_rx is
    constant IDLE      : std_logic_vector(1 downto 0) := "00";
    constant RUN       : std_logic_vector(1 downto 0) := "01";
    constant WAIT_HIGH : std_logic_vector(1 downto 0) := "10";
    constant START_CNT : unsigned(15 downto 0) := to_unsigned(1, 16);  -- cancels the synchroniser delay

    signal rx_v    : std_logic_vector(0 downto 0);
    signal rxd_v   : std_logic_vector(0 downto 0);
    signal rx      : std_logic;

    signal state   : std_logic_vector(1 downto 0);
    signal clk_cnt : unsigned(15 downto 0);
    signal bit_idx : unsigned(3 downto 0);
    signal votes   : std_logic_vector(1 downto 0);
    signal data_sr : std_logic_vector(7 downto 0);

    signal bit_len : unsigned(16 downto 0);
    signal mid     : unsigned(16 downto 0);
    signal sixth   : unsigned(16 downto 0);
    signal cnt     : unsigned(16 downto 0);
    signal bit_val : std_logic;
begin
    rxd_v(0) <= rxd;
    u_sync : entity work.tl_sync_2ff
        generic map (WIDTH => 1, RESET_VAL => 1)
        port map (clk => clk, rst => rst, async_in => rxd_v, sync_out => rx_v);
    rx <= rx_v(0);

    bit_len <= ('0' & unsigned(baud_div)) + 1;
    mid     <= '0' & bit_len(16 downto 1);
    sixth   <= "0000" & bit_len(16 downto 4);
    cnt     <= '0' & clk_cnt;
    bit_val <= (votes(0) and votes(1)) or (votes(0) and rx) or (votes(1) and rx);

    m_data <= data_sr;

    process (clk)
    begin
        if rising_edge(clk) then
            m_valid      <= '0';
            frame_error  <= '0';
            break_detect <= '0';
            if rst = '1' then
                state   <= IDLE;
                clk_cnt <= (others => '0');
                bit_idx <= (others => '0');
                votes   <= "11";
                data_sr <= (others => '0');
            else
                -- if/elsif, not case: GHDL 2.0's Verilog output drops the
                -- `when others` arm of a case (seen in the equivalence proof).
                if state = IDLE then
                    if rx = '0' then
                        state   <= RUN;
                        clk_cnt <= START_CNT;
                        bit_idx <= (others => '0');
                    end if;
                elsif state = RUN then
                    if clk_cnt = unsigned(baud_div) then
                        clk_cnt <= (others => '0');
                        bit_idx <= bit_idx + 1;
                    else
                        clk_cnt <= clk_cnt + 1;
                    end if;

                    if cnt = mid - sixth then
                        votes(0) <= rx;
                    end if;
                    if cnt = mid then
                        votes(1) <= rx;
                    end if;
                    if cnt = mid + sixth then
                        if bit_idx = 0 then
                            if bit_val = '1' then
                                state <= IDLE;    -- glitch, not a start bit
                            end if;
                        elsif bit_idx /= 9 then
                            data_sr <= bit_val & data_sr(7 downto 1);
                        elsif bit_val = '1' then
                            m_valid <= '1';
                            state   <= IDLE;
                        else
                            frame_error <= '1';
                            if data_sr = x"00" then
                                break_detect <= '1';
                            end if;
                            state <= WAIT_HIGH;
                        end if;
                    end if;
                else                          -- WAIT_HIGH
                    if rx = '1' then
                        state <= IDLE;
                    end if;
                end if;
            end if;
        end if;
    end process;
end architecture rtl;
