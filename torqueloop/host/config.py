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
from torqueloop.spec.pwm import carrier_hz

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


def _check_carriers(where: str, axes: list[dict[str, int]], globals_: dict[str, int]) -> None:
    """Every axis's PWM carrier at most PWM_MAX_HZ (the file's, or the bridge rating)."""
    ceiling = globals_.get("PWM_MAX_HZ", P.PARAMS["PWM_MAX_HZ"].max)
    for i, ax in enumerate(axes):
        if "FDIV" in ax and carrier_hz(ax["FDIV"]) > ceiling:
            raise HostConfigError(f"{where}.axes[{i}].FDIV = {ax['FDIV']}: carrier {carrier_hz(ax['FDIV']):.0f} Hz "
                                  f"above PWM_MAX_HZ {ceiling} Hz")


def _check_axis(where: str, ax: dict[str, int]) -> None:
    if "SOFT_MIN" in ax and "SOFT_MAX" in ax and ax["SOFT_MIN"] > ax["SOFT_MAX"]:
        raise HostConfigError(f"{where}: SOFT_MIN {ax['SOFT_MIN']} > SOFT_MAX {ax['SOFT_MAX']}")
    if "PW0" in ax and "PWMAX" in ax and ax["PW0"] > ax["PWMAX"]:
        raise HostConfigError(f"{where}: PW0 {ax['PW0']} > PWMAX {ax['PWMAX']} (eq. 1 needs PW0 <= PW_F)")
    if "TAU_MAX_MNM" in ax and "COUNTS_PER_REV" in ax:
        # the firmware keeps every raw gain within its physical gain's range
        raw_max = P.gain_raw_from_phys(P.PARAMS["KP_UNM_RAD"].max, ax["TAU_MAX_MNM"], ax["COUNTS_PER_REV"])
        for k in P.RAW_GAIN_OF:
            if ax.get(k, 0) > raw_max:
                raise HostConfigError(f"{where}.{k} = {ax[k]}: above {raw_max}, the raw gain of "
                                      f"{P.PARAMS['KP_UNM_RAD'].max / 1e6:g} N m/rad at this TAU_MAX_MNM and "
                                      "COUNTS_PER_REV")


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
    fw = doc.get("firmware")
    if fw is None:
        fw = {}
    if not isinstance(fw, dict):
        raise HostConfigError(f"{where}.firmware: must be an object, not {fw!r:.40}")
    bid = fw.get("build_id")
    if bid is None:
        build_id = None
    elif isinstance(bid, str):
        try:
            build_id = int(bid, 16)
        except ValueError:
            raise HostConfigError(f"{where}.firmware.build_id: {bid!r:.40} is not a hex number") from None
    elif isinstance(bid, int) and not isinstance(bid, bool):
        build_id = bid
    else:
        raise HostConfigError(f"{where}.firmware.build_id: {bid!r:.40} is not a number")
    if build_id is not None and not 0 <= build_id <= 0xFFFF_FFFF:
        raise HostConfigError(f"{where}.firmware.build_id: {build_id} is not a 32-bit build id")
    pv = fw.get("proto_version")
    if pv is not None and (isinstance(pv, bool) or not isinstance(pv, int)):
        raise HostConfigError(f"{where}.firmware.proto_version: {pv!r:.40} is not an integer")
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
    _check_carriers(where, out, globals_)
    return HostConfig(tuple(out), globals_, build_id, pv, "host")


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
    _check_carriers(str(path), axes, {})
    return HostConfig(tuple(axes), {}, None, None, "characterization")


def load_file(path: str | Path) -> HostConfig:
    p = Path(path)
    try:
        text = p.read_text(encoding="utf-8")
    except OSError as e:
        raise HostConfigError(f"{p}: cannot read ({e.strerror})") from None
    except UnicodeDecodeError:
        raise HostConfigError(f"{p}: not a text file (not UTF-8)") from None
    try:
        doc = json.loads(text)
    except json.JSONDecodeError as e:
        raise HostConfigError(f"{p}: not JSON ({e.msg} at line {e.lineno})") from None
    except RecursionError:
        raise HostConfigError(f"{p}: not a configuration file (JSON nested too deeply)") from None
    if isinstance(doc, dict) and doc.get("schema") == "torqueloop-characterization":
        return from_characterization(p)
    return parse(doc, str(p))


#: pairs the firmware keeps ordered at every step (low <= high), written as
#: low to its minimum, high, low: no intermediate state breaks the bound
_PAIRS = (("SOFT_MIN", "SOFT_MAX"), ("PW0", "PWMAX"))


def apply_order(cfg: HostConfig) -> list[tuple[int, str, int]]:
    """(axis, parameter, value) writes in an order the firmware accepts (all
    axes disabled): it refuses SOFT_MIN > SOFT_MAX, PW0 > PWMAX and a carrier
    above PWM_MAX_HZ at every step, so each low end is first taken to its
    minimum, the ceiling to the rating before the carriers and to its own
    value after them."""
    g = dict(cfg.globals)
    ceiling = g.pop("PWM_MAX_HZ", None)
    order: list[tuple[int, str, int]] = [(P.GLOBAL_AXIS, k, v) for k, v in g.items()]
    if ceiling is not None:
        order.append((P.GLOBAL_AXIS, "PWM_MAX_HZ", P.PARAMS["PWM_MAX_HZ"].max))
    for i, ax in enumerate(cfg.axes):
        gains = [k for k in P.RAW_GAIN_OF if k in ax]
        scale = [k for k in ("TAU_MAX_MNM", "COUNTS_PER_REV") if k in ax]
        if gains and scale:
            # a gain must fit its physical range at every step: zero them, scale, then set them
            order += [(i, k, 0) for k in gains] + [(i, k, ax[k]) for k in scale]
        for lo, hi in _PAIRS:
            if lo in ax or hi in ax:
                order.append((i, lo, P.PARAMS[lo].min))
                order += [(i, k, ax[k]) for k in (hi, lo) if k in ax]
        done = {k for pair in _PAIRS for k in pair} | (set(scale) if gains else set())
        order += [(i, k, v) for k, v in ax.items() if k not in done]
    if ceiling is not None:
        order.append((P.GLOBAL_AXIS, "PWM_MAX_HZ", ceiling))
    return order
