"""Step 8: the characterisation result as the build's configuration file.

The file is JSON (schema ``torqueloop-characterization``, version 1), one
entry per axis, holding what the frequency divider (eq. 2-4) and the PWM
torque block (eq. 1) need: ``count_max``, ``pw0_counts``, ``pw_max_counts``,
plus the chosen and achieved frequency and how the numbers were obtained.
It carries no date, so the same data give the same file byte for byte.
:func:`load_config` is the one reader: the host tool's ``config load`` and
the firmware/RTL build call it and get either a validated :class:`Config`
or a :class:`ConfigError` naming the field and the reason.

The divider arithmetic (eq. 4 and the frequency it really produces) is a
dependency, :class:`DividerModel`; the default is the frequency-divider
core's own reference model (torqueloop.models.freq_div), so the numbers
written here are the ones the RTL produces.
"""

from __future__ import annotations

import hashlib
import json
import math
import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Mapping, Protocol

from torqueloop.models import freq_div

from .method import MotorResult, Thresholds

SCHEMA = "torqueloop-characterization"
SCHEMA_VERSION = 1
CLK_HZ = 50_000_000  # DE0-CV CLOCK_50
PWM_BITS = 10  # gamma = 2^10, paper eq. (2)
DIV_BITS = freq_div.FreqDivParams().div_bits  # the divisor register width

_AXIS_RE = re.compile(r"^[a-z][a-z0-9_]{0,15}$")


class ConfigError(ValueError):
    """A configuration file the build must not use; ``str()`` names the field."""


class DividerModel(Protocol):
    """Eq. (2)-(4) as the frequency-divider core implements them."""

    name: str

    def count_max(self, f_motor_hz: float, clk_hz: int, pwm_bits: int) -> int: ...

    def achieved_hz(self, count_max: int, clk_hz: int, pwm_bits: int) -> float: ...


@dataclass(frozen=True)
class FunctionDivider:
    """A :class:`DividerModel` made of two functions (e.g. from torqueloop.models.freq_div)."""

    name: str
    count_max_fn: Callable[[float, int, int], int]
    achieved_hz_fn: Callable[[int, int, int], float]

    def count_max(self, f_motor_hz: float, clk_hz: int, pwm_bits: int) -> int:
        return int(self.count_max_fn(f_motor_hz, clk_hz, pwm_bits))

    def achieved_hz(self, count_max: int, clk_hz: int, pwm_bits: int) -> float:
        return float(self.achieved_hz_fn(count_max, clk_hz, pwm_bits))


def default_divider() -> DividerModel:
    """The frequency-divider core's reference model (torqueloop.models.freq_div):
    its eq. (4) Count_max and the carrier frequency pwm_torque then produces."""
    return FunctionDivider(
        "torqueloop.models.freq_div: count_max (eq. 4), carrier_hz",
        lambda f, clk, bits: freq_div.count_max(f, clk, bits, DIV_BITS),
        lambda n, clk, bits: freq_div.carrier_hz(n, clk, bits),
    )


def pwm_full_scale(pwm_bits: int) -> int:
    """M: duty counts per carrier period (pwm_torque: a period is 2^bits - 1
    ticks, duty M is constantly on; docs/pwm_torque.md)."""
    return (1 << pwm_bits) - 1


# ---------------------------------------------------------------- the file


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


def _sig(x: float, digits: int = 7) -> float:
    """Round to significant digits so that the file is stable across platforms."""
    return float(f"{x:.{digits}g}")


def _sha256(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def axis_config(
    result: MotorResult,
    *,
    clk_hz: int = CLK_HZ,
    pwm_bits: int = PWM_BITS,
    divider: DividerModel | None = None,
    base_dir: Path | None = None,
) -> AxisConfig:
    """Step 8 for one motor whose method result passed."""
    if result.status != "pass" or result.chosen is None or result.linearity is None:
        raise ValueError(f"step 8 needs a passing result, not {result.status!r}: {result.message}")
    div = divider or default_divider()
    lin, c = result.linearity, result.chosen
    f = c.freq_hz
    cm = div.count_max(f, clk_hz, pwm_bits)
    ach = div.achieved_hz(cm, clk_hz, pwm_bits)
    full = pwm_full_scale(pwm_bits)
    # PW0 rounded up: the first non-zero command must already move the motor
    # (eq. 1 maps it to PW0); one count too many is 0.1 % of torque.
    pw0 = int(math.ceil(lin.pw0_pct / 100.0 * full - 1e-9))
    pwmax = min(full, int(math.floor(lin.pwf_pct / 100.0 * full + 0.5)))
    if pw0 >= pwmax:
        raise ValueError(f"PW0 {pw0} counts is not below PW_F {pwmax} counts: no usable torque range")

    def rel(p: str) -> str:
        if base_dir is None:
            return Path(p).name
        try:
            return Path(p).resolve().relative_to(base_dir.resolve()).as_posix()
        except ValueError:
            return Path(p).name

    def inp(p: str) -> dict[str, str]:
        pp = Path(p)
        return {"file": rel(p), "sha256": _sha256(pp) if pp.is_file() else ""}

    tried = []
    for a in result.attempts:
        e: dict[str, Any] = {"freq_hz": _sig(a.candidate.freq_hz), "kind": a.candidate.kind}
        if a.linearity is not None and a.duty_sweep is not None:
            e["duty_sweep"] = rel(a.duty_sweep.source)
            e["passed"] = a.linearity.ok
            if not a.linearity.ok:
                e["reasons"] = a.linearity.reasons
        tried.append(e)
    inputs = [inp(result.freq_sweep.source)] + [
        inp(a.duty_sweep.source) for a in result.attempts if a.duty_sweep is not None
    ]
    # fixed decimals: values near zero must not carry platform-dependent noise
    checks = {ch.name: round(float(ch.value), 6) + 0.0 for ch in lin.checks}
    return AxisConfig(
        motor=result.freq_sweep.motor,
        pwm_freq_hz=_sig(f),
        count_max=cm,
        achieved_hz=_sig(ach),
        freq_error_pct=_sig(100.0 * (ach - f) / f, 4) + 0.0,  # no "-0.0"
        pw0_counts=pw0,
        pw_max_counts=pwmax,
        tau_max_nm=_sig(lin.tau_max_nm),
        duty_pw0_pct=_sig(lin.pw0_pct, 5),
        duty_pwf_pct=_sig(lin.pwf_pct, 5),
        torque_per_count_nm=_sig(lin.slope_nm_per_pct * 100.0 / full, 5),
        step7=checks,
        provenance={
            "inputs": inputs,
            "step5_target_nm": _sig(result.step5.target_nm),
            "duty_sweep_freq_hz": _sig(lin.freq_hz),
            "candidates_tried": tried,
        },
    )


def build_config(
    axes: Mapping[str, AxisConfig],
    thresholds: Thresholds,
    *,
    clk_hz: int = CLK_HZ,
    pwm_bits: int = PWM_BITS,
    divider: DividerModel | None = None,
) -> Config:
    from torqueloop import __version__

    div = divider or default_divider()
    for name in axes:
        if not _AXIS_RE.match(name):
            raise ValueError(f"axis name {name!r}: use a lower-case identifier (a-z, 0-9, _)")
    return Config(
        schema_version=SCHEMA_VERSION,
        clk_hz=clk_hz,
        pwm_bits=pwm_bits,
        axes=dict(sorted(axes.items())),
        provenance={
            "tool": f"torqueloop.characterize {__version__}",
            "method": "Lopez-Gomez et al., IEEE Access 2020, section II.B steps 2-8",
            "thresholds": thresholds.as_dict(),
            "divider_model": div.name,
        },
    )


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
    divider: DividerModel | None = None,
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
    div = divider or default_divider()
    axes: dict[str, AxisConfig] = {}
    for name, a in doc["axes"].items():
        w = f"{where_file}axes.{name}."
        if not _AXIS_RE.match(name):
            raise ConfigError(f"{where_file}axes.{name}: axis name must be a lower-case identifier")
        if not isinstance(a, Mapping):
            raise ConfigError(f"{where_file}axes.{name}: must be an object")
        _typed(w, a, _AXIS_FIELDS)
        if a["pwm_freq_hz"] <= 0:
            raise ConfigError(f"{w}pwm_freq_hz: must be > 0, got {a['pwm_freq_hz']}")
        if not 1 <= a["count_max"] < (1 << DIV_BITS):
            raise ConfigError(f"{w}count_max: must be 1 .. 2^{DIV_BITS}-1 (freq_div register), got {a['count_max']}")
        full = pwm_full_scale(bits)
        if not 0 <= a["pw0_counts"] < a["pw_max_counts"] <= full:
            raise ConfigError(
                f"{w}pw0_counts/pw_max_counts: need 0 <= pw0 < pw_max <= {full}, "
                f"got {a['pw0_counts']} / {a['pw_max_counts']}"
            )
        ach = div.achieved_hz(a["count_max"], clk, bits)
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


def c_header(cfg: Config, source_name: str = "characterization.json",
             pages: Mapping[str, int] | None = None) -> str:
    """A C11 header for the firmware build: per axis page the FDIV, PWM_PW0
    and PWM_PWMAX values, and ``tl_char_apply()`` writing them through the
    generated register header (firmware/include/torqueloop_regs.h)."""
    lines = [
        f"/* Generated by scripts/characterize.py from {source_name} - do not edit. */",
        "#ifndef TORQUELOOP_CHARACTERIZATION_H",
        "#define TORQUELOOP_CHARACTERIZATION_H",
        "",
        '#include "torqueloop_regs.h"',
        "",
    ]
    body = []
    for reg, _addr, val in register_writes(cfg, pages):
        body.append(f"#define TL_CHAR_{reg} {val}u")
    per_axis = {}
    pages = DEFAULT_AXIS_PAGES if pages is None else pages
    for name, a in cfg.axes.items():
        per_axis[name] = (
            f"/* axis {name} -> AXIS{pages[name]}: chosen {a.pwm_freq_hz:.6g} Hz, pins {a.achieved_hz:.6g} Hz "
            f"({a.freq_error_pct:+.3f} %), PW0 {a.duty_pw0_pct:.4g} %, tau_max {a.tau_max_nm:.5g} N m */"
        )
    for name in cfg.axes:
        lines.append(per_axis[name])
        lines += [b for b in body if b.startswith(f"#define TL_CHAR_AXIS{pages[name]}_")]
    lines += ["", "static inline void tl_char_apply(void)", "{"]
    for reg, _addr, _val in register_writes(cfg, pages):
        lines.append(f"    TL_{reg} = TL_CHAR_{reg};")
    lines += ["}", "", "#endif", ""]
    return "\n".join(lines)


def verilog_header(cfg: Config, source_name: str = "characterization.json",
                   pages: Mapping[str, int] | None = None) -> str:
    """`defines for an RTL build that wants the characterised values as reset
    defaults (same names as the C header)."""
    widths = {"FDIV": DIV_BITS, "PWM_PW0": cfg.pwm_bits, "PWM_PWMAX": cfg.pwm_bits}
    lines = [f"// Generated by scripts/characterize.py from {source_name} - do not edit."]
    for reg, _addr, val in register_writes(cfg, pages):
        w = widths[reg.split("_", 1)[1]]
        lines.append(f"`define TL_CHAR_{reg} {w}'d{val}")
    return "\n".join(lines) + "\n"
