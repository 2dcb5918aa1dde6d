# SPDX-License-Identifier: MIT
"""The characterisation configuration file: the one reader and writer.

Step 8 of the method writes it (torqueloop.characterize); the host tool's
``config load``, the experiment and the firmware/RTL build read it through
:func:`load_config`, which returns a validated :class:`Config` or raises a
:class:`ConfigError` naming the field and the reason.

The file is JSON (schema ``torqueloop-characterization``, version 1), one
entry per axis, holding what the frequency divider (eq. 2-4) and the PWM
torque block (eq. 1) need: ``count_max``, ``pw0_counts``, ``pw_max_counts``,
plus the chosen and achieved frequency and how the numbers were obtained.
It carries no date, so the same data give the same file byte for byte.
The divider arithmetic is torqueloop.spec.pwm's (the one definition), so
the numbers in the file are the ones the RTL produces.
"""

from __future__ import annotations

import json
import math
import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Mapping

from torqueloop.spec.pwm import carrier_hz, div_max, full_scale

SCHEMA = "torqueloop-characterization"
SCHEMA_VERSION = 1

AXIS_RE = re.compile(r"^[a-z][a-z0-9_]{0,15}$")


class ConfigError(ValueError):
    """A configuration file the build must not use; ``str()`` names the field."""



@dataclass(frozen=True)
class AxisConfig:
    motor: str
    pwm_freq_hz: float
    """step 5: the chosen motor frequency (the candidate that passed step 7)."""
    count_max: int
    """eq. (4): frequency-divider count for clk_hz and pwm_bits."""
    achieved_hz: float
    """the frequency the divider really gives with count_max."""
    freq_error_pct: float
    """100 (achieved - chosen) / chosen."""
    pw0_counts: int
    """eq. (1) dead zone PW0 in duty counts (of 2^pwm_bits - 1 per period)."""
    pw_max_counts: int
    """eq. (1) PW_F in counts: where the fitted line reaches tau_max."""
    tau_max_nm: float
    duty_pw0_pct: float
    duty_pwf_pct: float
    torque_per_count_nm: float
    step7: dict[str, Any] = field(default_factory=dict)
    provenance: dict[str, Any] = field(default_factory=dict)


@dataclass(frozen=True)
class Config:
    schema_version: int
    clk_hz: int
    pwm_bits: int
    axes: dict[str, AxisConfig]
    provenance: dict[str, Any] = field(default_factory=dict)


def sig(x: float, digits: int = 7) -> float:
    """Round to significant digits so that the file is stable across platforms."""
    return float(f"{x:.{digits}g}")


def config_to_json(cfg: Config) -> str:
    doc = {
        "schema": SCHEMA,
        "schema_version": cfg.schema_version,
        "clk_hz": cfg.clk_hz,
        "pwm_bits": cfg.pwm_bits,
        "axes": {
            name: {k: getattr(a, k) for k in _AXIS_FIELDS}
            for name, a in cfg.axes.items()
        },
        "provenance": cfg.provenance,
    }
    return json.dumps(doc, indent=2, sort_keys=True) + "\n"


def write_config(path: str | Path, cfg: Config) -> None:
    p = Path(path)
    p.parent.mkdir(parents=True, exist_ok=True)
    p.write_text(config_to_json(cfg), encoding="utf-8")


# ---------------------------------------------------------------- load


_AXIS_FIELDS: dict[str, type | tuple[type, ...]] = {
    "motor": str,
    "pwm_freq_hz": (int, float),
    "count_max": int,
    "achieved_hz": (int, float),
    "freq_error_pct": (int, float),
    "pw0_counts": int,
    "pw_max_counts": int,
    "tau_max_nm": (int, float),
    "duty_pw0_pct": (int, float),
    "duty_pwf_pct": (int, float),
    "torque_per_count_nm": (int, float),
    "step7": dict,
    "provenance": dict,
}
_TOP_FIELDS: dict[str, type | tuple[type, ...]] = {
    "schema": str,
    "schema_version": int,
    "clk_hz": int,
    "pwm_bits": int,
    "axes": dict,
    "provenance": dict,
}


def _typed(where: str, obj: Mapping[str, Any], fields: Mapping[str, type | tuple[type, ...]]) -> None:
    for k in obj:
        if k not in fields:
            raise ConfigError(f"{where}{k}: unknown field (known: {', '.join(sorted(fields))})")
    for k, t in fields.items():
        if k not in obj:
            raise ConfigError(f"{where}{k}: missing")
        v = obj[k]
        # bool is an int in Python; a true/false where a number belongs is a mistake
        if isinstance(v, bool) or not isinstance(v, t):
            want = t.__name__ if isinstance(t, type) else " or ".join(x.__name__ for x in t)
            raise ConfigError(f"{where}{k}: expected {want}, got {type(v).__name__} {v!r}")
        if isinstance(v, float) and not math.isfinite(v):
            raise ConfigError(f"{where}{k}: {v} is not a finite number")


def load_config(
    source: str | Path | Mapping[str, Any],
    *,
    max_freq_error_pct: float = 2.0,
) -> Config:
    """Read and validate a characterisation configuration.

    ``source``: a path, JSON text, or an already parsed mapping.  Checks the
    schema and version, every field's type, the ranges the RTL needs
    (1 <= count_max < 2^DIV_BITS, 0 <= pw0_counts < pw_max_counts <= 2^pwm_bits - 1),
    and that achieved_hz and freq_error_pct are what count_max really gives
    (so a hand-edited count cannot silently disagree with its frequency);
    ``|freq_error_pct| <= max_freq_error_pct``.
    """
    where_file = ""
    if isinstance(source, Mapping):
        doc: Any = source
    else:
        text: str
        if isinstance(source, Path) or (isinstance(source, str) and not source.lstrip().startswith("{")):
            p = Path(source)
            where_file = f"{p}: "
            try:
                text = p.read_text(encoding="utf-8")
            except OSError as e:
                raise ConfigError(f"{p}: cannot read ({e.strerror})") from None
        else:
            text = str(source)
        try:
            doc = json.loads(text)
        except json.JSONDecodeError as e:
            raise ConfigError(f"{where_file}line {e.lineno}: not valid JSON ({e.msg})") from None
    if not isinstance(doc, Mapping):
        raise ConfigError(f"{where_file}top level must be a JSON object")
    if doc.get("schema") != SCHEMA:
        raise ConfigError(f"{where_file}schema: expected {SCHEMA!r}, got {doc.get('schema')!r}")
    if doc.get("schema_version") != SCHEMA_VERSION:
        raise ConfigError(
            f"{where_file}schema_version: this reader understands {SCHEMA_VERSION}, got {doc.get('schema_version')!r}"
        )
    _typed(where_file, doc, _TOP_FIELDS)
    clk, bits = doc["clk_hz"], doc["pwm_bits"]
    if clk <= 0:
        raise ConfigError(f"{where_file}clk_hz: must be > 0, got {clk}")
    if not 1 <= bits <= 16:
        raise ConfigError(f"{where_file}pwm_bits: must be 1..16, got {bits}")
    if not doc["axes"]:
        raise ConfigError(f"{where_file}axes: no axis configured")
    axes: dict[str, AxisConfig] = {}
    for name, a in doc["axes"].items():
        w = f"{where_file}axes.{name}."
        if not AXIS_RE.match(name):
            raise ConfigError(f"{where_file}axes.{name}: axis name must be a lower-case identifier")
        if not isinstance(a, Mapping):
            raise ConfigError(f"{where_file}axes.{name}: must be an object")
        _typed(w, a, _AXIS_FIELDS)
        if a["pwm_freq_hz"] <= 0:
            raise ConfigError(f"{w}pwm_freq_hz: must be > 0, got {a['pwm_freq_hz']}")
        if not 1 <= a["count_max"] <= div_max():
            raise ConfigError(f"{w}count_max: must be 1 .. {div_max()} (freq_div register), got {a['count_max']}")
        full = full_scale(bits)
        if not 0 <= a["pw0_counts"] < a["pw_max_counts"] <= full:
            raise ConfigError(
                f"{w}pw0_counts/pw_max_counts: need 0 <= pw0 < pw_max <= {full}, "
                f"got {a['pw0_counts']} / {a['pw_max_counts']}"
            )
        ach = carrier_hz(a["count_max"], clk, bits)
        if not math.isclose(a["achieved_hz"], ach, rel_tol=1e-5):
            raise ConfigError(
                f"{w}achieved_hz: count_max {a['count_max']} gives {ach:.7g} Hz at clk_hz {clk}, "
                f"file says {a['achieved_hz']}"
            )
        err = 100.0 * (ach - a["pwm_freq_hz"]) / a["pwm_freq_hz"]
        if abs(err - a["freq_error_pct"]) > 1e-3 + 1e-3 * abs(err):
            raise ConfigError(f"{w}freq_error_pct: is {err:.4g} for these numbers, file says {a['freq_error_pct']}")
        if abs(err) > max_freq_error_pct:
            raise ConfigError(
                f"{w}count_max: {ach:.5g} Hz is {err:+.2f} % from the chosen {a['pwm_freq_hz']} Hz "
                f"(allowed {max_freq_error_pct} %)"
            )
        if a["tau_max_nm"] <= 0:
            raise ConfigError(f"{w}tau_max_nm: must be > 0, got {a['tau_max_nm']}")
        axes[name] = AxisConfig(**{k: a[k] for k in _AXIS_FIELDS})
    return Config(doc["schema_version"], clk, bits, axes, dict(doc["provenance"]))




# ---------------------------------------------------------------- to the board

#: Which SoC axis page drives which characterised axis: the plant's axis 1
#: (x) is AXIS0, axis 2 (z) is AXIS1 (sim_models/params/table2.toml order).
DEFAULT_AXIS_PAGES: dict[str, int] = {"x": 0, "z": 1}


def register_writes(cfg: Config, pages: Mapping[str, int] | None = None) -> list[tuple[str, int, int]]:
    """The SoC register writes that apply a configuration (torqueloop/spec/regmap.toml,
    AXIS page): (register name, address, value) for FDIV (Count_max),
    PWM_PW0 and PWM_PWMAX of each configured axis.  PW0/PW_max take effect
    at the next PWM period start (double-buffered in pwm_torque)."""
    from torqueloop.spec import regs

    pages = DEFAULT_AXIS_PAGES if pages is None else pages
    out = []
    for name, a in cfg.axes.items():
        if name not in pages:
            raise ConfigError(f"axes.{name}: no SoC axis page assigned (known: {dict(pages)})")
        p = f"AXIS{pages[name]}"
        for reg, val in (("FDIV", a.count_max), ("PWM_PW0", a.pw0_counts), ("PWM_PWMAX", a.pw_max_counts)):
            out.append((f"{p}_{reg}", int(getattr(regs, f"{p}_{reg}")), int(val)))
    return out


