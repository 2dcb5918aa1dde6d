# SPDX-License-Identifier: MIT
"""The characterisation method (paper II.B): bench sweeps in, the PWM
frequency and dead zone of each motor out, as the build's configuration.

    data    - the sweep CSV format, reading/writing with validation
    method  - steps 2, 5, 6-7 and the loop back to step 5
    config  - step 8: divider count (eq. 4), PW0 in counts (the file: torqueloop.spec.charconfig)
    plots   - Fig. 10 / Fig. 11 style figures
    conclude - steps 2-7's verdict per axis and step 8 (the file), shared by the command and the study
    simbench - the simulated lab bench (rope dynamometer, pins from the RTL or the cores' waveform)

The command (``torqueloop-study characterize``) and the study around the
method live on the applications floor, torqueloop/study/.

docs/characterization.md is the lab's guide.
"""

from torqueloop.spec.charconfig import AxisConfig, Config, ConfigError, load_config, write_config

from .config import CLK_HZ, PWM_BITS, axis_config, build_config
from .data import BenchConstants, DataError, Sweep, parse_sweep, read_sweep, write_sweep
from .method import (
    Candidate,
    Linearity,
    MethodError,
    MotorResult,
    Thresholds,
    characterize_motor,
    step5_candidates,
    steps67_linearity,
    tau_max_nm,
)

__all__ = [
    "CLK_HZ", "PWM_BITS", "AxisConfig", "Config", "ConfigError",
    "axis_config", "build_config", "load_config", "write_config",
    "BenchConstants", "DataError", "Sweep", "parse_sweep", "read_sweep", "write_sweep",
    "Candidate", "Linearity", "MethodError", "MotorResult", "Thresholds",
    "characterize_motor", "step5_candidates", "steps67_linearity", "tau_max_nm",
]
