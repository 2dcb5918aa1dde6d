# SPDX-License-Identifier: MIT
"""References from the other single sources to the system constants.

regmap.toml and protocol.toml write ``"system:<name>"`` where a value is a
system constant (or follows from one), so each number is stated once, in
system.toml.  A name resolves to one integer, or for ``per_axis`` names to
one integer per axis (a protocol parameter's per-axis defaults).
"""

from __future__ import annotations

from torqueloop.spec.pwm import divider_for
from torqueloop.spec.system import SYSTEM

PREFIX = "system:"

_P = SYSTEM.table1["P"]   # the firmware starts with the P law (Table 1) and its gains

#: name -> value; tuples are per axis
VALUES: dict[str, int | tuple[int, ...]] = {
    "clk_hz": SYSTEM.clk_hz,
    "pwm_full": SYSTEM.pwm_full,
    "div_max": (1 << SYSTEM.div_bits) - 1,
    "counts_per_turn": SYSTEM.counts_per_turn,
    "lead_um": SYSTEM.lead_um,
    "period_us": SYSTEM.period_us,
    "bridge_max_hz": SYSTEM.bridge_max_hz,
    # the FDIV register's reset value: axis 0's carrier (one reset value serves every AXIS page)
    "fdiv_reset": divider_for(SYSTEM.axes[0].pwm_hz),
    "fdiv": tuple(divider_for(a.pwm_hz) for a in SYSTEM.axes),
    "tau_max_mnm": tuple(a.tau_max_mnm for a in SYSTEM.axes),
    "no_load_cps": tuple(a.no_load_cps for a in SYSTEM.axes),
    "enc_tau_ms": tuple(a.enc_tau_ms for a in SYSTEM.axes),
    "kp_unm": tuple(g.micro()[0] for g in _P),
    "kd_unm": tuple(g.micro()[1] for g in _P),
    "ki_unm": tuple(g.micro()[2] for g in _P),
}


class RefError(ValueError):
    """A "system:" reference to a name that does not exist."""


def is_ref(v: object) -> bool:
    return isinstance(v, str) and v.startswith(PREFIX)


def resolve(v: object, where: str) -> int | tuple[int, ...]:
    """``v`` itself, or the value a "system:<name>" reference names."""
    if not is_ref(v):
        return v  # type: ignore[return-value]
    name = v[len(PREFIX):]  # type: ignore[index]
    if name not in VALUES:
        raise RefError(f"{where}: unknown system reference {v!r} (known: {', '.join(sorted(VALUES))})")
    return VALUES[name]
