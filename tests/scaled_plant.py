# SPDX-License-Identifier: MIT
"""The plant the identification and tuning tests stand in for "the user's
motors": lab-2025 with more friction and less inertia than any variant the
tools were told about, written as a plant file."""

from __future__ import annotations

import dataclasses
from pathlib import Path

from sim_models.params import PlantParams
from sim_models.plantfile import export_text
from sim_models.variants import load_variant

SCALE_FRICTION, SCALE_INERTIA = 1.25, 0.8


def scaled_lab_2025(folder: Path) -> tuple[PlantParams, Path]:
    """The scaled plant and the plant file it was written to in ``folder``."""
    p = load_variant("lab-2025")
    axes = tuple(a.replace(motor_coulomb_N_m=a.motor_coulomb_N_m * SCALE_FRICTION,
                           motor_static_N_m=a.motor_static_N_m * SCALE_FRICTION,
                           rotor_inertia_kg_m2=a.rotor_inertia_kg_m2 * SCALE_INERTIA) for a in p.axes)
    p = dataclasses.replace(p, axes=axes)
    f = folder / "scaled.toml"
    f.write_text(export_text(p, "lab-2025 scaled by the test"))
    return p, f
