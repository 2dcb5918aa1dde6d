# SPDX-License-Identifier: MIT
"""Parameter sets as data: dataclasses filled from a TOML file.

The default file is ``params/table2.toml`` (the paper's Table 2 with its unit
problems resolved; see docs/plant.md).  All values are SI; derived quantities
that the model and the docs use are properties, so they are computed in one
place.
"""

from __future__ import annotations

import dataclasses
import math
import tomllib
from dataclasses import dataclass, field
from pathlib import Path

DEFAULT_FILE = Path(__file__).resolve().parent / "params" / "table2.toml"


@dataclass(frozen=True)
class BridgeParams:
    supply_V: float = 12.0
    r_on_ohm: float = 0.016
    diode_V: float = 0.8
    k_ilis: float = 8500.0
    turn_on_delay_s: float = 3.6e-6
    turn_off_delay_s: float = 2.9e-6


@dataclass(frozen=True)
class EncoderParams:
    counts_per_motor_rev: int = 64
    index_every_counts: int = 64
    phase_offset_counts: float = 0.5

    @property
    def rad_per_count(self) -> float:
        return 2.0 * math.pi / self.counts_per_motor_rev


@dataclass(frozen=True)
class AxisParams:
    name: str
    resistance_ohm: float
    inductance_H: float
    ke_V_s_per_rad: float
    km_N_m_per_A: float
    rotor_inertia_kg_m2: float
    tau_max_paper_N_m: float
    pwm_hz_paper: float
    gear_ratio: float
    gear_efficiency: float
    gear_stiffness_N_m_per_rad: float
    gear_damping_N_m_s_per_rad: float
    gear_backlash_rad: float
    coupling_inertia_kg_m2: float
    coupling_stiffness_N_m_per_rad: float
    screw_inertia_kg_m2: float
    screw_torsion_N_m_per_rad: float
    screw_axial_N_per_m: float
    screw_axial_damping_N_s_per_m: float
    screw_mass_kg: float
    lead_m: float
    nut_stiffness_N_per_m: float
    nut_damping_N_s_per_m: float
    nut_clearance_m: float
    table_mass_kg: float
    table_coulomb_N: float
    gravity_m_s2: float

    # --- derived quantities (one place for model, tests and docs) ---
    @property
    def kt_motor_N_m_per_A(self) -> float:
        """Torque constant at the motor shaft: k_m is measured at the output
        shaft through the gearbox, so k_t = k_m / (xi G)."""
        return self.km_N_m_per_A / (self.gear_efficiency * self.gear_ratio)

    @property
    def screw_m_per_rad(self) -> float:
        """R_n of eq (11) with the screw efficiency taken as 1: S / 2 pi."""
        return self.lead_m / (2.0 * math.pi)

    @property
    def electrical_tau_s(self) -> float:
        return self.inductance_H / self.resistance_ohm

    def stall_current_A(self, volts: float) -> float:
        return volts / self.resistance_ohm

    def stall_torque_out_N_m(self, volts: float) -> float:
        return self.km_N_m_per_A * self.stall_current_A(volts)

    def no_load_motor_rad_s(self, volts: float) -> float:
        return volts / self.ke_V_s_per_rad

    @property
    def series_stiffness_out_N_m_per_rad(self) -> float:
        """Torsional stiffness from gearbox output to a clamped table, all
        springs in series, axial ones reflected through R_n^2."""
        rn2 = self.screw_m_per_rad**2
        inv = (1 / self.gear_stiffness_N_m_per_rad + 1 / self.coupling_stiffness_N_m_per_rad
               + 1 / self.screw_torsion_N_m_per_rad + 1 / (rn2 * self.nut_stiffness_N_per_m)
               + 1 / (rn2 * self.screw_axial_N_per_m))
        return 1.0 / inv

    def replace(self, **changes: float) -> "AxisParams":
        return dataclasses.replace(self, **changes)


@dataclass(frozen=True)
class PlantParams:
    axes: tuple[AxisParams, AxisParams]
    bridge: BridgeParams = field(default_factory=BridgeParams)
    encoder: EncoderParams = field(default_factory=EncoderParams)


def load_params(path: Path | str | None = None) -> PlantParams:
    """Load a plant parameter file (default: the paper's Table 2)."""
    with open(path or DEFAULT_FILE, "rb") as f:
        d = tomllib.load(f)
    axes = tuple(AxisParams(**d[k]) for k in ("axis1", "axis2"))
    return PlantParams(axes=axes,  # type: ignore[arg-type]
                       bridge=BridgeParams(**d.get("bridge", {})),
                       encoder=EncoderParams(**d.get("encoder", {})))
