# SPDX-License-Identifier: MIT
"""``config save`` / ``config load``: the board's parameters as a JSON file.

Schema ``torqueloop-host-config`` version 1::

    {"schema": "torqueloop-host-config", "schema_version": 1,
     "firmware": {"build_id": "0x1234abcd", "fw_version": 256, "proto_version": 1},
     "global": {"PERIOD_US": 25000, ...},
     "axes": [{"LAW": 1, "KP_Q16": 17132, ...}, {...}],
     "readable": {"axes": [{"kp_N_m_per_rad": 0.82, ...}]}}

Gains are stored raw (q16): the exact integers the controller runs with, so
save -> load -> save gives the same file.  The ``readable`` block repeats
them in physical units for people; it is ignored on load.  BAUD_DIV is not
stored: restoring it would cut the link the file is being loaded over.

``config load`` also accepts the characterisation flow's file
(``torqueloop-characterization``, read by
:func:`torqueloop.characterize.config.load_config`, its one reader): per axis
it sets FDIV = count_max, PW0 = pw0_counts, PWMAX = pw_max_counts and
TAU_MAX_MNM from tau_max_nm.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from torqueloop.spec import protocol as P
from torqueloop.spec.charconfig import ConfigError, load_config

SCHEMA = "torqueloop-host-config"
SCHEMA_VERSION = 1
NOT_SAVED = frozenset({"BAUD_DIV",
                       # derived views of the q16 gains (the firmware converts)
                       "KP_UNM_RAD", "KD_UNMS_RAD", "KI_UNM_RADS"})
AXIS_PARAMS = [p.name for p in P.PARAMS.values() if p.scope == "axis" and p.name not in NOT_SAVED]
GLOBAL_PARAMS = [p.name for p in P.PARAMS.values() if p.scope == "global" and p.name not in NOT_SAVED]
# Characterisation axis names to axis numbers (sim_models: axis 0 = x, 1 = z).
CHAR_AXES = {"x": 0, "z": 1, "0": 0, "1": 1, "axis0": 0, "axis1": 1}


class HostConfigError(ValueError):
    """A file ``config load`` must not apply; ``str()`` names the field."""


@dataclass(frozen=True)
class HostConfig:
    """What ``config load`` writes: per-axis and global raw values."""

    axes: tuple[dict[str, int], ...]
    globals: dict[str, int]
    build_id: int | None
    proto_version: int | None
    source: str        # "host" or "characterization"


def _check_value(where: str, name: str, v: Any) -> int:
    if name not in P.PARAMS:
        raise HostConfigError(f"{where}: unknown parameter {name!r}")
    if isinstance(v, bool) or not isinstance(v, int):
        raise HostConfigError(f"{where}.{name}: must be an integer, not {v!r}")
    p = P.PARAMS[name]
    if not p.min <= v <= p.max:
        raise HostConfigError(f"{where}.{name} = {v} outside [{p.min}, {p.max}]")
    return v


def _check_axis(where: str, ax: dict[str, int]) -> None:
    if "SOFT_MIN" in ax and "SOFT_MAX" in ax and ax["SOFT_MIN"] > ax["SOFT_MAX"]:
        raise HostConfigError(f"{where}: SOFT_MIN {ax['SOFT_MIN']} > SOFT_MAX {ax['SOFT_MAX']}")
    if "PW0" in ax and "PWMAX" in ax and ax["PW0"] > ax["PWMAX"]:
        raise HostConfigError(f"{where}: PW0 {ax['PW0']} > PWMAX {ax['PWMAX']} (eq. 1 needs PW0 <= PW_F)")


def to_json(cfg: HostConfig, readable: dict[str, Any] | None = None) -> str:
    doc: dict[str, Any] = {
        "schema": SCHEMA, "schema_version": SCHEMA_VERSION,
        "firmware": {"build_id": None if cfg.build_id is None else f"0x{cfg.build_id:08x}",
                     "proto_version": cfg.proto_version},
        "global": {k: cfg.globals[k] for k in GLOBAL_PARAMS if k in cfg.globals},
        "axes": [{k: ax[k] for k in AXIS_PARAMS if k in ax} for ax in cfg.axes],
    }
    if readable:
        doc["readable"] = readable
    return json.dumps(doc, indent=2) + "\n"


def parse(doc: Any, where: str = "config") -> HostConfig:
    """Validate a parsed host-config document (every value, in range, complete)."""
    if not isinstance(doc, dict):
        raise HostConfigError(f"{where}: not a JSON object")
    if doc.get("schema") != SCHEMA:
        raise HostConfigError(f"{where}: schema is {doc.get('schema')!r}, expected {SCHEMA!r}")
    if doc.get("schema_version") != SCHEMA_VERSION:
        raise HostConfigError(f"{where}: schema_version {doc.get('schema_version')!r}, this tool reads "
                              f"{SCHEMA_VERSION}")
    fw = doc.get("firmware") or {}
    bid = fw.get("build_id")
    try:
        build_id = None if bid is None else int(bid, 16) if isinstance(bid, str) else int(bid)
    except ValueError:
        raise HostConfigError(f"{where}.firmware.build_id: {bid!r} is not a number") from None
    g = doc.get("global")
    if not isinstance(g, dict):
        raise HostConfigError(f"{where}.global: missing or not an object")
    globals_ = {k: _check_value(f"{where}.global", k, v) for k, v in g.items()}
    for k in globals_:
        if P.PARAMS[k].scope != "global" or k in NOT_SAVED:
            raise HostConfigError(f"{where}.global.{k}: not a global parameter this file may set")
    axes = doc.get("axes")
    if not isinstance(axes, list) or len(axes) != P.AXIS_COUNT:
        raise HostConfigError(f"{where}.axes: must be a list of {P.AXIS_COUNT} objects")
    out = []
    for i, ax in enumerate(axes):
        w = f"{where}.axes[{i}]"
        if not isinstance(ax, dict):
            raise HostConfigError(f"{w}: not an object")
        vals = {k: _check_value(w, k, v) for k, v in ax.items()}
        for k in vals:
            if P.PARAMS[k].scope != "axis" or k in NOT_SAVED:
                raise HostConfigError(f"{w}.{k}: not an axis parameter this file may set")
        missing = [k for k in AXIS_PARAMS if k not in vals]
        if missing:
            raise HostConfigError(f"{w}: missing {', '.join(missing)}")
        _check_axis(w, vals)
        out.append(vals)
    return HostConfig(tuple(out), globals_, build_id, fw.get("proto_version"), "host")


def from_characterization(path: Path) -> HostConfig:
    """The characterisation flow's file through its one validating reader."""
    try:
        c = load_config(path)
    except ConfigError as e:
        raise HostConfigError(str(e)) from None
    axes: list[dict[str, int]] = [{} for _ in range(P.AXIS_COUNT)]
    for name, a in c.axes.items():
        if name not in CHAR_AXES:
            raise HostConfigError(f"{path}: axis {name!r} is not one of {sorted(CHAR_AXES)}")
        w = f"{path}: axes.{name}"
        vals = {"FDIV": a.count_max, "PW0": a.pw0_counts, "PWMAX": a.pw_max_counts,
                "TAU_MAX_MNM": int(round(a.tau_max_nm * 1000))}
        axes[CHAR_AXES[name]] = {k: _check_value(w, k, v) for k, v in vals.items()}
        _check_axis(w, axes[CHAR_AXES[name]])
    return HostConfig(tuple(axes), {}, None, None, "characterization")


def load_file(path: str | Path) -> HostConfig:
    p = Path(path)
    try:
        text = p.read_text(encoding="utf-8")
    except OSError as e:
        raise HostConfigError(f"{p}: cannot read ({e.strerror})") from None
    try:
        doc = json.loads(text)
    except json.JSONDecodeError as e:
        raise HostConfigError(f"{p}: not JSON ({e.msg} at line {e.lineno})") from None
    if isinstance(doc, dict) and doc.get("schema") == "torqueloop-characterization":
        return from_characterization(p)
    return parse(doc, str(p))


def apply_order(cfg: HostConfig) -> list[tuple[int, str, int]]:
    """(axis, parameter, value) writes in an order the firmware accepts: it
    refuses SOFT_MIN > SOFT_MAX at every step, so the lower limit is first
    widened to its minimum, then SOFT_MAX and SOFT_MIN take their values."""
    order: list[tuple[int, str, int]] = [(P.GLOBAL_AXIS, k, v) for k, v in cfg.globals.items()]
    for i, ax in enumerate(cfg.axes):
        if "SOFT_MIN" in ax or "SOFT_MAX" in ax:
            order.append((i, "SOFT_MIN", P.PARAMS["SOFT_MIN"].min))
            order += [(i, k, ax[k]) for k in ("SOFT_MAX", "SOFT_MIN") if k in ax]
        order += [(i, k, v) for k, v in ax.items() if k not in ("SOFT_MIN", "SOFT_MAX")]
    return order
