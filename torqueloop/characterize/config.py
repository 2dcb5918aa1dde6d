# SPDX-License-Identifier: MIT
"""Step 8: a passing method result as the build's configuration (the file
format and its reader are torqueloop.spec.charconfig's; the C / Verilog
headers that bake it into a firmware or RTL build are torqueloop.flow.gen_charconfig's)."""

from __future__ import annotations

import hashlib
import math
from pathlib import Path
from typing import Any, Mapping

from torqueloop.spec.charconfig import AXIS_RE, SCHEMA_VERSION, AxisConfig, Config, sig
from torqueloop.spec.pwm import carrier_hz, divider_for, full_scale
from torqueloop.spec.system import SYSTEM

from .method import MotorResult, Thresholds

CLK_HZ = SYSTEM.clk_hz
PWM_BITS = SYSTEM.pwm_bits
DIVIDER = "torqueloop.spec.pwm: divider_for (eq. 4, nearest carrier), carrier_hz"


def _sha256(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def axis_config(
    result: MotorResult,
    *,
    clk_hz: int = CLK_HZ,
    pwm_bits: int = PWM_BITS,
    base_dir: Path | None = None,
) -> AxisConfig:
    """Step 8 for one motor whose method result passed."""
    if result.status != "pass" or result.chosen is None or result.linearity is None:
        raise ValueError(f"step 8 needs a passing result, not {result.status!r}: {result.message}")
    lin, c = result.linearity, result.chosen
    f = c.freq_hz
    cm = divider_for(f, clk_hz, pwm_bits)
    ach = carrier_hz(cm, clk_hz, pwm_bits)
    full = full_scale(pwm_bits)
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
        e: dict[str, Any] = {"freq_hz": sig(a.candidate.freq_hz), "kind": a.candidate.kind}
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
        pwm_freq_hz=sig(f),
        count_max=cm,
        achieved_hz=sig(ach),
        freq_error_pct=sig(100.0 * (ach - f) / f, 4) + 0.0,  # no "-0.0"
        pw0_counts=pw0,
        pw_max_counts=pwmax,
        tau_max_nm=sig(lin.tau_max_nm),
        duty_pw0_pct=sig(lin.pw0_pct, 5),
        duty_pwf_pct=sig(lin.pwf_pct, 5),
        torque_per_count_nm=sig(lin.slope_nm_per_pct * 100.0 / full, 5),
        step7=checks,
        provenance={
            "inputs": inputs,
            "step5_target_nm": sig(result.step5.target_nm),
            "duty_sweep_freq_hz": sig(lin.freq_hz),
            "candidates_tried": tried,
        },
    )


def build_config(
    axes: Mapping[str, AxisConfig],
    thresholds: Thresholds,
    *,
    clk_hz: int = CLK_HZ,
    pwm_bits: int = PWM_BITS,
) -> Config:
    from torqueloop import __version__

    for name in axes:
        if not AXIS_RE.match(name):
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
            "divider_model": DIVIDER,
        },
    )
