# SPDX-License-Identifier: MIT
"""Layer 0, the specification: the single sources of the system and the one
definition of every equation the project implements in more than one place.

- :mod:`.repo`      where the source tree is (flows that need the checkout)
- :mod:`.system`    system constants (``system.toml``): clock, PWM bits,
  counts per turn, lead, the paper's tau_max and Table 1 gains
- :mod:`.regmap`    the SoC memory and register map (``regmap.toml``),
  :mod:`.regs` its constants by name
- :mod:`.protocol`  the link protocol (``protocol.toml``) and its frame codec
- :mod:`.refs`      ``"system:<key>"`` references from the other TOML files
- :mod:`.auth`      the link's authentication (HMAC-SHA-256 sessions, key files)
- :mod:`.bootproto` the bootloader's wire protocol and image format
- :mod:`.charconfig` the characterisation file and the register writes it means
- :mod:`.bridge`    the IBT-2's pins and its two off-phase states
- :mod:`.pwm`       eq. (1)-(4): the frequency divider and duty mapping
- :mod:`.metrics`   step metrics and the RMSE of eq. (26)-(27)
- :mod:`.units`     positions and gains in physical units

Data and definitions only: what is written from them (headers, packages,
docs) is torqueloop.flow's.  Depends on nothing else of ours
(torqueloop/flow/layers.py checks it), so the host tool, the oracles, the
plant, the flows and the simulations can all import it.
"""
