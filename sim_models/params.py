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


class PlantParamError(ValueError):
    """A parameter file or variant with a missing, unknown or non-physical value."""


@dataclass(frozen=True)
class BridgeParams:
    supply_V: float = 12.0
    r_on_ohm: float = 0.016
    diode_V: float = 0.8
    k_ilis: float = 8500.0
    turn_on_delay_s: float = 3.6e-6
    turn_off_delay_s: float = 2.9e-6
    # --- the bridge's switching in the plant (the ``lab`` variant's
    # bridge_timing effect; off: the plant switches exactly at the pin edges) ---
    timing_in_plant: bool = False
    """Delay each output edge by turn_on_delay_s / turn_off_delay_s and drop
    driving pulses shorter than min_pulse_s (sim_models.stepper.FastAxis)."""
    min_pulse_s: float = 0.0
    """Shortest driving phase (at the pins) the outputs reproduce; shorter
    ones never reach the rail and are dropped."""


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
    # --- what a real bench has and Table 2 leaves out (the ``lab`` variant,
    # sim_models/variants.py; all off in the paper's variants) ---
    motor_coulomb_N_m: float = 0.0       # brush and bearing Coulomb friction, motor shaft
    motor_static_N_m: float = 0.0        # breakaway (stiction) at the motor shaft, >= coulomb
    brush_drop_V: float = 0.0            # brush contact drop, opposes the current while it flows
    gear_efficiency_back: float | None = None
    """Efficiency while the load back-drives the motor; None is the paper's
    symmetric form (xi on the output side in both directions of power flow)."""
    brush_knee_A: float = 0.0
    """Brush voltage-current law: 0 is the hard drop (brush_drop_V whenever
    current flows); > 0 makes the brushes ohmic (brush_drop_V / brush_knee_A)
    below this current and brush_drop_V above it."""
    winding_alpha_per_K: float = 0.0
    """Winding resistance temperature coefficient: R = R_20 (1 + alpha theta),
    theta the winding's rise over ambient (0: R constant)."""
    winding_thermal_K_per_W: float = 0.0
    """Winding-to-ambient thermal resistance (0: no heating)."""
    winding_thermal_tau_s: float = 0.0
    """Time constant of the winding's first-order thermal model."""

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

    @property
    def heats(self) -> bool:
        """Whether the winding's resistance follows its temperature."""
        return self.winding_thermal_K_per_W > 0.0 and self.winding_alpha_per_K > 0.0

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

    def motor_stall_torque_N_m(self, bridge: "BridgeParams") -> float:
        """k_t V / R with the bridge's supply and path: the rotor torque at
        stall (the scale the lab variant's friction is stated against)."""
        return self.kt_motor_N_m_per_A * bridge.supply_V / (self.resistance_ohm + 2 * bridge.r_on_ohm)

    def replace(self, **changes: float) -> "AxisParams":
        return dataclasses.replace(self, **changes)

    def validate(self, bridge: "BridgeParams", where: str = "") -> None:
        """Refuse a non-physical value with one line naming the key and the rule."""
        w = f"{where}{self.name}." if where or self.name else ""
        positive = ("resistance_ohm", "inductance_H", "ke_V_s_per_rad", "km_N_m_per_A", "rotor_inertia_kg_m2",
                    "gear_ratio", "gear_efficiency", "gear_stiffness_N_m_per_rad", "coupling_inertia_kg_m2",
                    "coupling_stiffness_N_m_per_rad", "screw_inertia_kg_m2", "screw_torsion_N_m_per_rad",
                    "screw_axial_N_per_m", "screw_mass_kg", "lead_m", "nut_stiffness_N_per_m", "table_mass_kg")
        non_negative = ("gear_damping_N_m_s_per_rad", "gear_backlash_rad", "screw_axial_damping_N_s_per_m",
                        "nut_damping_N_s_per_m", "nut_clearance_m", "table_coulomb_N", "gravity_m_s2",
                        "motor_coulomb_N_m", "motor_static_N_m", "brush_drop_V", "brush_knee_A",
                        "winding_alpha_per_K", "winding_thermal_K_per_W", "winding_thermal_tau_s")
        for k in positive + non_negative:
            v = getattr(self, k)
            if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
                raise PlantParamError(f"{w}{k} = {v!r}: must be a finite number")
            if k in positive and not v > 0:
                raise PlantParamError(f"{w}{k} = {v}: must be positive")
            if k in non_negative and v < 0:
                raise PlantParamError(f"{w}{k} = {v}: must not be negative")
        for k in ("gear_efficiency", "gear_efficiency_back"):
            v = getattr(self, k)
            if v is not None and not 0 < v <= 1:
                raise PlantParamError(f"{w}{k} = {v}: an efficiency must be in (0, 1]")
        if self.motor_static_N_m < self.motor_coulomb_N_m:
            raise PlantParamError(f"{w}motor_static_N_m = {self.motor_static_N_m}: breakaway below the "
                                  f"Coulomb level {self.motor_coulomb_N_m} (static friction is at least sliding)")
        stall = self.motor_stall_torque_N_m(bridge)
        if self.motor_static_N_m >= stall:
            raise PlantParamError(f"{w}motor_static_N_m = {self.motor_static_N_m}: friction at or above the "
                                  f"stall torque {stall:.4g} N m (the motor could never turn)")
        if self.winding_thermal_K_per_W > 0 and not self.winding_thermal_tau_s > 0:
            raise PlantParamError(f"{w}winding_thermal_tau_s = {self.winding_thermal_tau_s}: a heated winding "
                                  "needs a positive thermal time constant")
        if self.brush_drop_V >= bridge.supply_V:
            raise PlantParamError(f"{w}brush_drop_V = {self.brush_drop_V}: at or above the {bridge.supply_V} V supply")


@dataclass(frozen=True)
class PlantParams:
    axes: tuple[AxisParams, AxisParams]
    bridge: BridgeParams = field(default_factory=BridgeParams)
    encoder: EncoderParams = field(default_factory=EncoderParams)


def _make(cls: type, d: dict, where: str) -> object:
    names = {f.name for f in dataclasses.fields(cls)}
    required = {f.name for f in dataclasses.fields(cls)
                if f.default is dataclasses.MISSING and f.default_factory is dataclasses.MISSING}
    for k in d:
        if k not in names:
            raise PlantParamError(f"{where}{k}: unknown parameter")
    for k in sorted(required - set(d)):
        raise PlantParamError(f"{where}{k}: missing")
    return cls(**d)


def params_from_dict(d: dict, source: str = "") -> PlantParams:
    """A PlantParams from the parsed TOML layout (sections bridge, encoder,
    axis1, axis2), every value checked (:meth:`AxisParams.validate`)."""
    where = f"{source}: " if source else ""
    for k in ("axis1", "axis2"):
        if not isinstance(d.get(k), dict):
            raise PlantParamError(f"{where}[{k}]: missing")
    bridge: BridgeParams = _make(BridgeParams, d.get("bridge", {}), f"{where}bridge.")  # type: ignore[assignment]
    for k in ("supply_V", "k_ilis"):
        if not getattr(bridge, k) > 0:
            raise PlantParamError(f"{where}bridge.{k} = {getattr(bridge, k)}: must be positive")
    if not 0 <= bridge.min_pulse_s <= bridge.turn_off_delay_s:
        raise PlantParamError(f"{where}bridge.min_pulse_s = {bridge.min_pulse_s}: must be in [0, turn_off_delay_s] "
                              "(a pulse is dropped before its output has started)")
    axes = tuple(_make(AxisParams, d[k], f"{where}{k}.") for k in ("axis1", "axis2"))
    for a in axes:
        a.validate(bridge, where)  # type: ignore[attr-defined]
    return PlantParams(axes=axes,  # type: ignore[arg-type]
                       bridge=bridge,
                       encoder=_make(EncoderParams, d.get("encoder", {}), f"{where}encoder."))  # type: ignore[arg-type]


def read_toml(path: Path | str) -> dict:
    try:
        with open(path, "rb") as f:
            return tomllib.load(f)
    except OSError as e:
        raise PlantParamError(f"{path}: cannot read ({e.strerror})") from None
    except tomllib.TOMLDecodeError as e:
        raise PlantParamError(f"{path}: not valid TOML ({e})") from None


def load_params(path: Path | str | None = None) -> PlantParams:
    """Load a plant parameter file (default: the paper's Table 2 as printed;
    sim_models.variants names the readings built on it)."""
    p = path or DEFAULT_FILE
    return params_from_dict(read_toml(p), str(p))
