# SPDX-License-Identifier: MIT
# Timing constraints of the torqueloop board top: generated from constraints/pins.toml by torqueloop.flow.generate.
# Do not edit: change the pin table and run .venv/bin/python -m torqueloop.flow.generate

# CLOCK_50: 50 MHz oscillator: the only clock of the design
create_clock -name CLOCK_50 -period 20.000 [get_ports {CLOCK_50}]
derive_pll_clocks
derive_clock_uncertainty

# Asynchronous inputs: each goes through a synchroniser (sync_2ff, or reset_sync for
# RESET_N) before any logic reads it, so no timing relation to CLOCK_50 exists.
set_false_path -from [get_ports {RESET_N KEY[0] KEY[1] KEY[2] KEY[3] SW[0] SW[1] SW[2]}]
set_false_path -from [get_ports {SW[3] SW[4] SW[5] SW[6] SW[7] SW[8] SW[9] GPIO_0[4]}]
set_false_path -from [get_ports {GPIO_0[6] GPIO_0[7] GPIO_0[8] GPIO_0[5] GPIO_0[9] GPIO_0[10] GPIO_0[12] GPIO_1[4]}]
set_false_path -from [get_ports {GPIO_1[6] GPIO_1[7] GPIO_1[8] GPIO_1[5] GPIO_1[9]}]

# Outputs from registers to LEDs, displays, H-bridge inputs (PWM up to 25 kHz, 20 ns
# resolution) and the 3.3 V UART: a few ns of pin delay change nothing for them.
set_false_path -to [get_ports {LEDR[0] LEDR[1] LEDR[2] LEDR[3] LEDR[4] LEDR[5] LEDR[6] LEDR[7]}]
set_false_path -to [get_ports {LEDR[8] LEDR[9] HEX0[0] HEX0[1] HEX0[2] HEX0[3] HEX0[4] HEX0[5]}]
set_false_path -to [get_ports {HEX0[6] HEX1[0] HEX1[1] HEX1[2] HEX1[3] HEX1[4] HEX1[5] HEX1[6]}]
set_false_path -to [get_ports {HEX2[0] HEX2[1] HEX2[2] HEX2[3] HEX2[4] HEX2[5] HEX2[6] HEX3[0]}]
set_false_path -to [get_ports {HEX3[1] HEX3[2] HEX3[3] HEX3[4] HEX3[5] HEX3[6] HEX4[0] HEX4[1]}]
set_false_path -to [get_ports {HEX4[2] HEX4[3] HEX4[4] HEX4[5] HEX4[6] HEX5[0] HEX5[1] HEX5[2]}]
set_false_path -to [get_ports {HEX5[3] HEX5[4] HEX5[5] HEX5[6] GPIO_0[0] GPIO_0[1] GPIO_0[2] GPIO_0[3]}]
set_false_path -to [get_ports {GPIO_0[11] GPIO_0[13] GPIO_1[0] GPIO_1[1] GPIO_1[2] GPIO_1[3]}]
