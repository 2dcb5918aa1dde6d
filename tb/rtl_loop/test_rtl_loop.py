# SPDX-License-Identifier: MIT
"""RTL in the loop, short version of the paper's step experiment (make test).

The board image runs the real servo firmware (firmware/servo) on the native
Verilator harness; the sim_models plant closes the loop through the bridge
and encoder pins; the host configures and commands it over the UART with the
protocol module.  P law, Table 1 gains, 6.28 rad step on both axes, a 5 ms
control period (the paper's is 25 ms) so that axis x settles within the 2 s
simulated.  Checks what a user of `make run` relies on:
  - RTL in the loop agrees with the pure model: position RMSE (eq. 26-27)
    at most 1 % of the step, velocity RMSE bounded;
  - axis x ends inside the 2 % band of the target, as the model does, and
    within a few counts of it;
  - the firmware saw no fault, every control sample reached the host.
The full experiment is `make run` (scripts/run_experiment.py).
"""

from __future__ import annotations

import math
import os

import pytest

from torqueloop.sim import experiment, report

T_END_S = 2.0
PERIOD_US = 5_000


def _wanted() -> bool:
    sims = os.environ.get("TORQUELOOP_SIM", "").strip()
    return not sims or "verilator" in [s.strip() for s in sims.split(",")]


@pytest.mark.skipif(not _wanted(), reason="the RTL-in-the-loop test runs on Verilator only")
def test_rtl_loop_verilator_native() -> None:
    cfg = experiment.ExperimentConfig(law="P", t_end_s=T_END_S, period_us=PERIOD_US, progress=False)
    rtl = experiment.run_rtl(cfg)
    model = experiment.run_model(cfg)
    cmp = report.compare(rtl, model)
    step = cfg.target_counts * 2 * math.pi / experiment.COUNTS_PER_REV
    print(f"RMSE position {cmp['rmse_rad']:.4f} rad ({cmp['rmse_pct_of_step']:.2f} % of the step), "
          f"velocity {cmp['rmse_rad_s']:.4f} rad/s; {rtl.cycles:,} clocks in {rtl.wall_s:.1f} s wall / "
          f"{rtl.cpu_s:.1f} s CPU; bridge {rtl.bridge}")
    assert rtl.faults == [0], f"fault flags {rtl.faults}"
    assert rtl.config_faults == [0, 0], f"configuring the period latched faults {rtl.config_faults}"
    assert rtl.link_errors == 0 and rtl.uart_errors == 0
    assert cmp["rmse_rad"] <= 0.01 * step, cmp
    # velocity: both are the same filtered Euler estimate of whole counts
    assert cmp["rmse_rad_s"] <= 0.05 * 5.3, cmp      # 5 % of axis x's peak speed
    x_rtl = cmp["per_axis"]["x"]["rtl"]
    x_model = cmp["per_axis"]["x"]["model"]
    assert x_model["settling_time_s"] is not None, "the model itself did not settle: test set-up wrong"
    assert x_rtl["settling_time_s"] is not None, x_rtl
    assert abs(x_rtl["steady_state_error_counts"]) <= 0.02 * cfg.target_counts, x_rtl
    assert abs(x_rtl["steady_state_error_counts"] - x_model["steady_state_error_counts"]) <= 20, (x_rtl, x_model)
    # the plant really moved: the true screw angle follows the telemetry position
    assert abs(rtl.traj.true_pos[-1, 0] - rtl.traj.pos[-1, 0]) < 2 * math.pi / experiment.COUNTS_PER_REV * 2
