# SPDX-License-Identifier: MIT
"""BTS7960 / IBT-2 H-bridge: pin states in, armature voltage and IS current out.

Each BTS7960 is a half-bridge: with its enable (INH, the module's R_EN/L_EN)
high, IN (RPWM/LPWM) high switches the high side on, low switches the low
side on; with the enable low both switches are off and the output floats, so
motor current can only flow through the body diodes.  Half-bridge A (R side)
drives motor terminal M+, half-bridge B (L side) drives M-; positive armature
current flows A -> motor -> B.

While a side floats, the voltage it presents depends on the current's sign
(the diode that conducts), so the bridge gives two armature voltages:
``e_pos`` (valid while i > 0) and ``e_neg`` (valid while i < 0).  When both
sides are driven they are equal.  When i = 0 and the back-EMF lies between
them, no diode conducts and the current stays at zero (discontinuous
conduction, handled by the axis model as a mode).
"""

from __future__ import annotations

from sim_models.params import BridgeParams
from torqueloop.spec.bridge import BRAKE, COAST, Pins  # noqa: F401  (re-exported: the plant's pin vocabulary)

H, L, Z = 0, 1, 2  # half-bridge output states: high side on, low side on, off


def half_state(pwm: int, en: int) -> int:
    return Z if not en else (H if pwm else L)


def armature_voltages(pins: Pins, p: BridgeParams) -> tuple[float, float]:
    """(e_pos, e_neg): armature voltage while i > 0 and while i < 0 (V)."""
    a = half_state(pins.rpwm, pins.r_en)
    b = half_state(pins.lpwm, pins.l_en)
    vs, vf = p.supply_V, p.diode_V
    # terminal A: current leaves it when i > 0 (low-side diode conducts if off)
    va_pos = vs if a == H else (0.0 if a == L else -vf)
    va_neg = vs if a == H else (0.0 if a == L else vs + vf)
    # terminal B: current enters it when i > 0 (high-side diode conducts if off)
    vb_pos = vs if b == H else (0.0 if b == L else vs + vf)
    vb_neg = vs if b == H else (0.0 if b == L else -vf)
    return va_pos - vb_pos, va_neg - vb_neg


def path_resistance(p: BridgeParams) -> float:
    """Two switches (or diodes, approximated by the same resistance) in the path."""
    return 2.0 * p.r_on_ohm


def is_currents(pins: Pins, current_A: float, p: BridgeParams) -> tuple[float, float]:
    """(R_IS, L_IS) pin currents in A: the BTS7960 senses the forward current
    of its high-side switch and sources it divided by k_ILIS.  Diode and
    low-side current is not sensed.  The fault level (4-7 mA) is not modelled:
    the model never reaches the 43 A current limit."""
    r = current_A / p.k_ilis if half_state(pins.rpwm, pins.r_en) == H and current_A > 0 else 0.0
    l_ = -current_A / p.k_ilis if half_state(pins.lpwm, pins.l_en) == H and current_A < 0 else 0.0
    return r, l_
