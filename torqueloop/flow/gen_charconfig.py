# SPDX-License-Identifier: MIT
"""A characterisation file (torqueloop.spec.charconfig) as a C header for a
firmware build or as Verilog defines for an RTL build
(``torqueloop-study characterize export``): written on request from a
user's file, so not among the committed products of flow/generate.py."""

from __future__ import annotations

from typing import Mapping

from torqueloop.flow.licence import banner
from torqueloop.spec.charconfig import DEFAULT_AXIS_PAGES, Config, register_writes
from torqueloop.spec.system import SYSTEM

WRITER = "torqueloop-study characterize export"


def c_header(cfg: Config, source_name: str = "characterization.json",
             pages: Mapping[str, int] | None = None) -> str:
    """A C11 header for the firmware build: per axis page the FDIV, PWM_PW0
    and PWM_PWMAX values, and ``tl_char_apply()`` writing them through the
    generated register header (firmware/include/torqueloop_regs.h)."""
    lines = [
        banner(".h", source_name, WRITER),
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
    widths = {"FDIV": SYSTEM.div_bits, "PWM_PW0": cfg.pwm_bits, "PWM_PWMAX": cfg.pwm_bits}
    lines = [banner(".v", source_name, WRITER)]
    for reg, _addr, val in register_writes(cfg, pages):
        w = widths[reg.split("_", 1)[1]]
        lines.append(f"`define TL_CHAR_{reg} {w}'d{val}")
    return "\n".join(lines) + "\n"
