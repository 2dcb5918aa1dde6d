# SPDX-License-Identifier: MIT
"""Layer 0, the specification: the single sources of the system and the one
definition of every equation the project implements in more than one place.

- :mod:`.repo`      where the source tree is (flows that need the checkout)
- :mod:`.system`    system constants (``system.toml``): clock, PWM bits,
  counts per turn, lead, the paper's tau_max and Table 1 gains
- :mod:`.regmap`    the SoC memory and register map (``regmap.toml``),
  :mod:`.regs` its constants by name
- :mod:`.protocol`  the link protocol (``protocol.toml``) and its frame codec
- :mod:`.bootproto` the bootloader's wire protocol and image format
- :mod:`.pins`      the board pin table (``constraints/pins.toml``)
- :mod:`.pwm`       eq. (1)-(4): the frequency divider and duty mapping
- :mod:`.metrics`   step metrics and the RMSE of eq. (26)-(27)
- :mod:`.units`     positions and gains in physical units

Depends on nothing else of ours (tests/test_layers.py checks it), so the
host tool, the models, the flows and the simulations can all import it.
"""
