# SPDX-License-Identifier: MIT
"""RTL-in-the-loop co-simulation: the board image (firmware on the SoC)
closing the loop through its pins with the sim_models plant.

Modules:
  native    build + ctypes wrapper of the native Verilator harness (harness/harness.cpp)
  pins      plant on the bridge pins: speculative plant step, encoder edges as pin events
  link      host side of the UART link (torqueloop.spec.protocol frames) over any byte pipe
  experiment  the paper's step experiment (sec. VI.B) on the RTL and on the pure model
  report    plots, report.json and the Markdown summary (build/report/)
"""
