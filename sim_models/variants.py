# SPDX-License-Identifier: MIT
"""Named plant variants: ``paper-printed``, ``paper`` (the default), ``lab-2025`` and ``lab``.

Each variant is the paper's Table 2 (params/table2.toml) with overlays
(params/variants.toml): ``paper`` reads I_m2 as a misprint, ``lab`` adds what
a real bench has and Table 2 leaves out, one switchable effect at a time
(docs/plant.md argues every value); ``lab-2025`` is ``lab`` as first built,
before NEW_EFFECTS::

    from sim_models.variants import load_variant
    p = load_variant("lab")                               # every effect on
    p = load_variant("lab", off=("brush_drop",))          # one effect off
    p = load_variant("lab", off=EFFECTS)                  # == load_variant("paper")
    p = plant_of("lab-no-brush_drop").params()            # a command line's choice, parsed once
    p = load_variant("lab", off=NEW_EFFECTS)              # == load_variant("lab-2025")

An unknown name, an unknown effect or a non-physical value raises
:class:`PlantVariantError` with one line naming the key and the rule.
"""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path
from typing import Iterable

from sim_models.params import (DEFAULT_FILE, AxisParams, BridgeParams, PlantParamError, PlantParams,
                               params_from_dict, read_toml)

VARIANTS_FILE = Path(__file__).resolve().parent / "params" / "variants.toml"
DEFAULT_VARIANT = "paper"
#: the lab variant's effects, in the order they are applied
EFFECTS = ("motor_friction", "brush_drop", "gear_efficiency", "energy_consistent",
           "bridge_timing", "brush_law", "winding_thermal", "gear_backlash")
#: the effects lab-2025 does not have
NEW_EFFECTS = EFFECTS[4:]
#: effects on the bridge (one for both axes) rather than on each axis
BRIDGE_EFFECTS = ("bridge_timing",)


class PlantVariantError(PlantParamError):
    """An unknown variant or effect, or an overlay that breaks a rule."""


def _table() -> dict:
    return read_toml(VARIANTS_FILE)


def names() -> tuple[str, ...]:
    return tuple(_table())


def describe(name: str) -> str:
    return str(_spec(name).get("description", ""))


def _spec(name: str) -> dict:
    t = _table()
    if name not in t:
        raise PlantVariantError(f"unknown plant variant {name!r} (known: {', '.join(t)})")
    return t[name]


def _base_dict(name: str, seen: tuple[str, ...] = ()) -> dict:
    """The parameter layout of a variant before its effects: Table 2 and the
    axis overlays of the variant and its bases."""
    if name in seen:
        raise PlantVariantError(f"variants.toml: base cycle {' -> '.join((*seen, name))}")
    spec = _spec(name)
    d = _base_dict(spec["base"], (*seen, name)) if "base" in spec else read_toml(DEFAULT_FILE)
    d = {k: dict(v) if isinstance(v, dict) else v for k, v in d.items()}
    for sec in ("bridge", "encoder", "axis1", "axis2"):
        for k, v in spec.get(sec, {}).items():
            d.setdefault(sec, {})[k] = v
    return d


def _effects(name: str) -> dict[str, dict]:
    """The effects of a variant (its own and its bases'), by name."""
    spec = _spec(name)
    out = _effects(spec["base"]) if "base" in spec else {}
    for k, v in spec.get("effect", {}).items():
        if k not in EFFECTS:
            raise PlantVariantError(f"variants.toml: {name}.effect.{k}: unknown effect (known: {', '.join(EFFECTS)})")
        out[k] = v
    return out


def _num(eff: str, cfg: dict, key: str, lo: float, hi: float, *, lo_open: bool = False) -> float:
    v = cfg.get(key)
    if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
        raise PlantVariantError(f"effect.{eff}.{key} = {v!r}: must be a finite number")
    if v < lo or (lo_open and v == lo) or v > hi:
        raise PlantVariantError(f"effect.{eff}.{key} = {v}: must be in {'(' if lo_open else '['}{lo}, {hi}]")
    return float(v)


def back_efficiency(forward: float, stages: int) -> float:
    """Back-driving efficiency of a gear train whose tooth friction is
    proportional to the transmitted load: per stage forward 1 / (1 + e),
    back-driving 1 - e."""
    per = forward ** (1.0 / stages)
    e = 1.0 / per - 1.0
    return (1.0 - e) ** stages


def apply_effect(a: AxisParams, eff: str, cfg: dict, supply_V: float, r_path_ohm: float) -> AxisParams:
    """One lab effect on one axis's parameters."""
    if eff == "motor_friction":
        stall = a.kt_motor_N_m_per_A * supply_V / (a.resistance_ohm + r_path_ohm)
        cf = _num(eff, cfg, "coulomb_frac", 0.0, 1.0)
        sf = _num(eff, cfg, "static_frac", 0.0, 1.0)
        return a.replace(motor_coulomb_N_m=cf * stall, motor_static_N_m=sf * stall)
    if eff == "brush_drop":
        return a.replace(brush_drop_V=_num(eff, cfg, "volts", 0.0, supply_V))
    if eff == "gear_efficiency":
        stages = cfg.get("stages")
        if isinstance(stages, bool) or not isinstance(stages, int) or stages < 1:
            raise PlantVariantError(f"effect.{eff}.stages = {stages!r}: must be a whole number >= 1")
        if "back" in cfg:
            back = _num(eff, cfg, "back", 0.0, 1.0, lo_open=True)
        else:
            back = back_efficiency(a.gear_efficiency, stages)
        return a.replace(gear_efficiency_back=back)
    if eff == "energy_consistent":
        return a.replace(ke_V_s_per_rad=a.kt_motor_N_m_per_A)
    if eff == "brush_law":
        return a.replace(brush_knee_A=_num(eff, cfg, "knee_A", 0.0, 1e3, lo_open=True))
    if eff == "winding_thermal":
        return a.replace(winding_alpha_per_K=_num(eff, cfg, "alpha_per_K", 0.0, 0.1),
                         winding_thermal_K_per_W=_num(eff, cfg, "thermal_K_per_W", 0.0, 1e3),
                         winding_thermal_tau_s=_num(eff, cfg, "tau_s", 0.0, 1e5, lo_open=True))
    if eff == "gear_backlash":
        return a.replace(gear_backlash_rad=math.radians(_num(eff, cfg, "play_deg", 0.0, 30.0)) / 2.0)
    raise PlantVariantError(f"unknown effect {eff!r} (known: {', '.join(EFFECTS)})")


def load_variant(name: str = DEFAULT_VARIANT, off: Iterable[str] = (),
                 tweak: dict[str, dict] | None = None) -> PlantParams:
    """The plant parameters of a named variant, with the named effects off;
    ``tweak`` replaces effect parameters ({"brush_drop": {"volts": 1.0}}), for
    sensitivity studies."""
    off = tuple(off)
    tweak = tweak or {}
    for e in tweak:
        if e not in EFFECTS:
            raise PlantVariantError(f"unknown effect {e!r} (known: {', '.join(EFFECTS)})")
    for e in off:
        if e not in EFFECTS:
            raise PlantVariantError(f"unknown effect {e!r} (known: {', '.join(EFFECTS)})")
    base = params_from_dict(_base_dict(name), f"variant {name}")
    axes = list(base.axes)
    bridge = base.bridge
    for eff, cfg in _effects(name).items():
        enabled = cfg.get("enabled", True)
        if not isinstance(enabled, bool):
            raise PlantVariantError(f"effect.{eff}.enabled = {enabled!r}: must be true or false")
        if not enabled or eff in off:
            continue
        cfg = {**cfg, **tweak.get(eff, {})}
        if eff in BRIDGE_EFFECTS:
            bridge = apply_bridge_effect(bridge, eff, cfg)
            continue
        axes = [apply_effect(a, eff, cfg, bridge.supply_V, 2 * bridge.r_on_ohm) for a in axes]
    for a in axes:
        a.validate(bridge, f"variant {name}: ")
    return dataclasses.replace(base, axes=tuple(axes), bridge=bridge)


def apply_bridge_effect(b: BridgeParams, eff: str, cfg: dict) -> BridgeParams:
    """One lab effect on the bridge."""
    if eff == "bridge_timing":
        mp = _num(eff, cfg, "min_pulse_us", 0.0, b.turn_off_delay_s * 1e6) * 1e-6
        return dataclasses.replace(b, timing_in_plant=True, min_pulse_s=mp)
    raise PlantVariantError(f"unknown bridge effect {eff!r} (known: {', '.join(BRIDGE_EFFECTS)})")


def effects_of(name: str) -> tuple[str, ...]:
    """The effects a variant switches on (lab: all of EFFECTS)."""
    return tuple(k for k, v in _effects(name).items() if v.get("enabled", True))


@dataclasses.dataclass(frozen=True)
class PlantSpec:
    """A plant variant with some of its effects switched off, or a plant file
    (sim_models/plantfile.py): what a study passes around instead of the name
    (:func:`plant_of` parses and checks the name once, at the edge;
    :meth:`from_file` reads and checks a file once)."""

    name: str = DEFAULT_VARIANT
    off: tuple[str, ...] = ()
    file: str | None = None
    digest: str = ""          # a plant file's content digest (caches keyed by the plant see an edit)

    @classmethod
    def from_file(cls, path: str | Path) -> "PlantSpec":
        from sim_models.plantfile import load_plant_file
        import hashlib

        load_plant_file(path)          # refuses a bad file in one line (PlantParamError) before anything runs
        text = Path(path).read_bytes()
        return cls(name="file", file=str(Path(path).resolve()), digest=hashlib.sha256(text).hexdigest()[:16])

    @property
    def label(self) -> str:
        """The name a command line gives it: ``NAME[-no-EFFECT...]``, or the plant file's path."""
        if self.file is not None:
            return f"{self.file} ({self.digest})"
        return self.name + "".join(f"-no-{e}" for e in self.off)

    def params(self, tweak: dict[str, dict] | None = None) -> PlantParams:
        if self.file is not None:
            from sim_models.plantfile import load_plant_file

            if tweak:
                raise PlantVariantError(f"{self.file}: a plant file has no effects to tweak; edit the file")
            return load_plant_file(self.file)
        return load_variant(self.name, self.off, tweak)

    def without(self, effect: str) -> "PlantSpec":
        if self.file is not None:
            raise PlantVariantError(f"{self.file}: a plant file has no effects to switch off; edit the file")
        return PlantSpec(self.name, (*self.off, effect))


def plant_choice(name: str | None, file: str | None, default: str = DEFAULT_VARIANT) -> PlantSpec:
    """The plant a command line chose with ``--plant NAME`` or ``--plant-file
    FILE`` (not both), checked once."""
    if file is not None:
        if name is not None:
            raise PlantVariantError("give --plant or --plant-file, not both")
        return PlantSpec.from_file(file)
    return plant_of(name if name is not None else default)


def plant_of(text: "str | PlantSpec") -> PlantSpec:
    """A command-line plant choice, ``NAME`` or ``NAME-no-EFFECT[-no-EFFECT...]``
    (``lab-no-brush_drop``), checked (:class:`PlantVariantError` names what is
    unknown); a :class:`PlantSpec` is returned as it is."""
    if isinstance(text, PlantSpec):
        return text
    name, *offs = text.split("-no-")
    load_variant(name, offs)   # refuses an unknown name or effect
    return PlantSpec(name, tuple(offs))
