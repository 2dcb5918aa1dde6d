# SPDX-License-Identifier: MIT
"""Plant models of the torqueloop two-axis ball-screw stage (paper sec. III-IV).

Modules:
- :mod:`sim_models.params`  parameter dataclasses loaded from ``params/table2.toml``
- :mod:`sim_models.bridge`  BTS7960 H-bridge: pin states -> armature voltage, IS current
- :mod:`sim_models.axis`    one axis as a piecewise-affine hybrid system (eq 5-17)
- :mod:`sim_models.stepper` fast exact-ZOH stepper and the two-axis co-simulation API
- :mod:`sim_models.reference` stiff scipy (Radau) reference integration
- :mod:`sim_models.encoder` quadrature encoder (A/B/Z) from motor-shaft angle
- :mod:`sim_models.dyno`    dynamometer bench of the characterisation method (sec. II)
- :mod:`torqueloop.sim.model_loop` pure-model P/PD/PID closed loop (eq 20-22, Table 1)
- :mod:`sim_models.waveforms` input waveforms on the 50 MHz grid for the plant's tests and benchmarks

docs/plant.md documents equations, interpretations and validation numbers.
"""

from sim_models.params import AxisParams, BridgeParams, EncoderParams, PlantParams, load_params

__all__ = ["AxisParams", "BridgeParams", "EncoderParams", "PlantParams", "load_params"]
