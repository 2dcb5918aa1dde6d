# SPDX-License-Identifier: MIT
"""The plant file: a whole plant as one TOML file a person can read and edit.

Layout (every key names its quantity and its SI unit; docs/plant.md lists
them; docs/identification.md)::

    [meta]       format = 1, source (the variant or file it was written from), description
    [bridge]     supply_V, r_on_ohm, ...                  BridgeParams
    [encoder]    counts_per_motor_rev, ...                EncoderParams
    [axis1]      name = "x", resistance_ohm, ...          AxisParams, every field
    [axis2]      name = "z", ...
    [identifiable.x], [identifiable.z]
                 what an encoder-only identification sees (sim_models/identifiable.py):
                 written by the export, ignored when the file is read as a plant
                 (an identification writes its estimates there, with <key>_sigma beside each)

:func:`export_text` writes any plant; :func:`load_plant_file` reads one back
through the same checks as the variants (params_from_dict: a missing,
unknown or non-physical value is refused in one line naming the key and
the rule).  Export then load gives the same PlantParams, bit for bit (floats
are written with repr).
"""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

from sim_models.identifiable import identifiable_plant
from sim_models.params import PlantParamError, PlantParams, params_from_dict, read_toml
from torqueloop.spec.system import SYSTEM

FORMAT = 1
#: sections of the file that are not plant parameters
META, IDENTIFIABLE = "meta", "identifiable"


def _value(v: object) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, int):
        return str(v)
    if isinstance(v, float):
        if not math.isfinite(v):
            raise PlantParamError(f"{v!r} cannot be written to a plant file")
        return repr(v)
    if isinstance(v, str):
        return '"' + v.replace("\\", "\\\\").replace('"', '\\"') + '"'
    raise TypeError(f"no TOML form for {v!r}")


def _section(name: str, rows: dict[str, object]) -> list[str]:
    return [f"[{name}]", *(f"{k} = {_value(v)}" for k, v in rows.items() if v is not None), ""]


def _fields(obj: object) -> dict[str, object]:
    return {f.name: getattr(obj, f.name) for f in dataclasses.fields(obj)}


def export_text(p: PlantParams, source: str, description: str = "",
                carrier_hz: float = SYSTEM.working_hz, measured: dict[str, dict[str, float]] | None = None) -> str:
    """The plant file of ``p`` (``source``: the variant name or file it came
    from); the identifiable dead zones at ``carrier_hz``.  ``measured``: an
    identification's estimates (with their ``_sigma``) for some axes, written
    in their ``[identifiable.<axis>]`` sections instead of the closed forms."""
    lines = ["# torqueloop plant file: SI units, each key names its unit (docs/identification.md, 'The plant file').",
             "# [identifiable.*] is what an encoder-only identification can see; it is not read back as a plant.",
             ""]
    lines += _section(META, {"format": FORMAT, "source": source, "description": description})
    lines += _section("bridge", _fields(p.bridge))
    lines += _section("encoder", _fields(p.encoder))
    for i, a in enumerate(p.axes, start=1):
        lines += _section(f"axis{i}", _fields(a))
    for axis, ident in identifiable_plant(p, carrier_hz).items():
        rows = (measured or {}).get(axis, ident.as_dict())
        lines += _section(f"{IDENTIFIABLE}.{axis}", {"carrier_hz": float(carrier_hz), **rows})
    return "\n".join(lines)


def plant_dict(d: dict, source: str) -> dict:
    """The plant parameters of a parsed plant file (meta checked, the
    identification's section set aside)."""
    meta = d.get(META, {})
    fmt = meta.get("format") if isinstance(meta, dict) else None
    if fmt != FORMAT:
        raise PlantParamError(f"{source}: [meta] format = {fmt!r}: this torqueloop reads plant files of format {FORMAT}")
    return {k: v for k, v in d.items() if k not in (META, IDENTIFIABLE)}


def load_plant_file(path: Path | str) -> PlantParams:
    """A plant from a plant file, every value checked."""
    return params_from_dict(plant_dict(read_toml(path), str(path)), str(path))


def identified(path: Path | str) -> dict[str, dict[str, float]]:
    """The [identifiable.<axis>] sections of a plant file (empty if none)."""
    d = read_toml(path).get(IDENTIFIABLE, {})
    return {k: dict(v) for k, v in d.items() if isinstance(v, dict)}


def plant_from_identified(base: PlantParams, axis: int, est: dict[str, float], winding_ohm: float,
                          carrier_hz: float = SYSTEM.working_hz) -> PlantParams:
    """A plant whose ``axis`` reproduces an identification's estimates, the
    rest (springs, screw, table, the other axis) kept from ``base``: k_e = k_t
    = the back-EMF constant, the winding resistance as measured, the rotor
    inertia what the estimate leaves after the reflected load, the brush drop
    as a hard drop, the rotor's Coulomb friction what the estimates leave after
    the base's table friction (and gravity), and its breakaway found so that
    the closed form's dead zone at ``carrier_hz`` is the measured one (the
    mean of both directions).  The plant model has no viscous term: a
    viscous estimate is not carried."""
    from sim_models.axis import AxisConsts
    from sim_models.identifiable import _motor_load, identifiable, rigid_inertia_at_motor

    a = base.axes[axis]
    k = est["back_emf_v_s_per_rad"]
    a = a.replace(ke_V_s_per_rad=k, km_N_m_per_A=k * a.gear_efficiency * a.gear_ratio, resistance_ohm=winding_ohm,
                  brush_knee_A=0.0, brush_drop_V=max(0.0, (est.get("brush_drop_pos_v", 0.0)
                                                               + est.get("brush_drop_neg_v", 0.0)) / 2),
                  motor_coulomb_N_m=0.0, motor_static_N_m=0.0)
    c = AxisConsts.build(a, base.bridge)
    behind = rigid_inertia_at_motor(c) - a.rotor_inertia_kg_m2
    a = a.replace(rotor_inertia_kg_m2=max(1e-12, est["inertia_at_motor_kg_m2"] - behind))
    load = (_motor_load(c, +1, c.fc) - _motor_load(c, -1, c.fc)) / 2
    tc = max(0.0, (est["coulomb_pos_n_m"] + est["coulomb_neg_n_m"]) / 2 - load)
    a = a.replace(motor_coulomb_N_m=tc, motor_static_N_m=tc)
    want = (est["dead_zone_pos_pct"] + est["dead_zone_neg_pct"]) / 2
    stall = a.motor_stall_torque_N_m(base.bridge)
    lo, hi = tc, 0.99 * stall

    def dz(ts: float) -> float:
        i = identifiable(a.replace(motor_static_N_m=ts), base.bridge, carrier_hz)
        return (i.dead_zone_pos_pct + i.dead_zone_neg_pct) / 2

    if dz(lo) < want:
        for _ in range(60):
            mid = (lo + hi) / 2
            lo, hi = (mid, hi) if dz(mid) < want else (lo, mid)
        a = a.replace(motor_static_N_m=hi)
    axes = list(base.axes)
    axes[axis] = a
    a.validate(base.bridge, "identified: ")
    return dataclasses.replace(base, axes=tuple(axes))
