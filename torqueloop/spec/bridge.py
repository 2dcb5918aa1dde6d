# SPDX-License-Identifier: MIT
"""The IBT-2 (two BTS7960 half-bridges) logic interface of one axis: the pin
tuple every model of the board drives and the plant reads (board README).

RPWM/LPWM switch the R/L half-bridge's high side on (1) or its low side on
(0) while that side's enable is high; an enable low floats its side.
"""

from __future__ import annotations

from typing import NamedTuple


class Pins(NamedTuple):
    """IBT-2 logic inputs of one axis (1 = high)."""

    rpwm: int
    lpwm: int
    r_en: int
    l_en: int


BRAKE = Pins(0, 0, 1, 1)   # both low sides on: slow decay (pwm_torque's off phase and safe state)
COAST = Pins(0, 0, 0, 0)   # both sides off: fast decay through the diodes
FORWARD = Pins(1, 0, 1, 1)
REVERSE = Pins(0, 1, 1, 1)


def on_pins(cmd: int) -> Pins:
    """The on phase of a PWM period for a command's sign (IBT-2 mode: PWM on
    RPWM forward, on LPWM reverse, both enables high)."""
    return FORWARD if cmd > 0 else REVERSE
