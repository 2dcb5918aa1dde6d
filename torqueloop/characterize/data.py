# SPDX-License-Identifier: MIT
"""The bench data format: the two sweeps of the characterisation method.

A lab records, per motor, one *frequency sweep* at a fixed 50 % duty
(paper II.B steps 3-4) and one or more *duty sweeps* (step 6), each at a
candidate frequency chosen by step 5.  Each file is a self-describing CSV:

    # format = torqueloop-sweep-1
    # sweep = frequency            (or: duty)
    # motor = motor 1              (free text label)
    # wheel_radius_m = 0.025       (bench constants, paper II.A)
    # theta_deg = 90
    # supply_v = 12
    # duty_pct = 50                (frequency sweep: the fixed duty)
    # stall_force_n = 96.0         (frequency sweep: step 2, 100 % on)
    # stall_current_a = 2.27
    # freq_hz = 447.95             (duty sweep: the PWM frequency it ran at)
    freq_hz,force_n,current_a      (duty sweep: duty_pct,force_n,current_a)
    50,47.1,1.13
    ...

Units are in the names (SI, except percent and degrees).  Instead of the
dynamometer force (``force_n``, ``stall_force_n``) a file may give the torque
directly (``torque_nm``, ``stall_torque_nm``); tau = r F sin(theta) (II.A) is
applied to forces.  An optional ``current_std_a`` column records how much the
ammeter reading wandered at each point (the paper's "stable current").
Other columns are allowed and ignored (notes, raw readings).

Everything a file gets wrong is refused with the line and the reason
(:class:`DataError`): the method must never run on data it misread.
"""

from __future__ import annotations

import csv
import io
import math
import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Literal

import numpy as np

FORMAT_TAG = "torqueloop-sweep-1"

# The fewest points each step can work with: step 5 interpolates between
# neighbours and needs a curve, not a pair; steps 6-7 fit a line to the
# points beyond the dead zone and need several there (checked again, with
# the dead zone known, by the method).
MIN_FREQ_POINTS = 4
MIN_DUTY_POINTS = 6

SweepKind = Literal["frequency", "duty"]


class DataError(ValueError):
    """A sweep file the method must not use.  ``str()`` is ``file:line: reason``."""

    def __init__(self, source: str, line: int | None, reason: str) -> None:
        self.source = source
        self.line = line
        self.reason = reason
        where = f"{source}:{line}" if line is not None else source
        super().__init__(f"{where}: {reason}")


@dataclass(frozen=True)
class BenchConstants:
    """The structural platform (paper II.A, Fig. 1): wheel of radius r on the
    shaft, rope at angle theta to the radius, motor at its supply voltage."""

    wheel_radius_m: float
    theta_deg: float
    supply_v: float

    def torque_nm(self, force_n: np.ndarray | float) -> np.ndarray | float:
        """tau = r F sin(theta), paper II.A / step 2."""
        return self.wheel_radius_m * np.asarray(force_n, dtype=float) * math.sin(math.radians(self.theta_deg))

    def matches(self, other: "BenchConstants", rel: float = 1e-6) -> bool:
        return all(
            math.isclose(a, b, rel_tol=rel)
            for a, b in (
                (self.wheel_radius_m, other.wheel_radius_m),
                (self.theta_deg, other.theta_deg),
                (self.supply_v, other.supply_v),
            )
        )


@dataclass(frozen=True)
class Sweep:
    """One recorded sweep, already converted to torque.

    ``x`` is the swept variable: frequency in Hz (``kind == "frequency"``) or
    duty in percent (``kind == "duty"``); strictly increasing.
    """

    kind: SweepKind
    motor: str
    bench: BenchConstants
    x: np.ndarray
    torque_nm: np.ndarray
    current_a: np.ndarray
    current_std_a: np.ndarray | None = None
    # frequency sweep: the fixed duty and the step-2 stall measurement
    duty_pct: float | None = None
    stall_torque_nm: float | None = None
    stall_current_a: float | None = None
    # duty sweep: the PWM frequency it was recorded at
    freq_hz: float | None = None
    source: str = "<memory>"
    # the file's raw form, kept for provenance (hash) and round trips
    force_given: bool = True
    meta: dict[str, str] = field(default_factory=dict)

    @property
    def x_name(self) -> str:
        return "freq_hz" if self.kind == "frequency" else "duty_pct"


_META_RE = re.compile(r"^#\s*([A-Za-z_][A-Za-z0-9_]*)\s*=\s*(.*?)\s*$")


def _num(source: str, line: int, name: str, text: str) -> float:
    try:
        v = float(text)
    except ValueError:
        raise DataError(source, line, f"{name} = {text!r} is not a number") from None
    if not math.isfinite(v):
        raise DataError(source, line, f"{name} is {text.strip()} (NaN or infinite)")
    return v


def parse_sweep(text: str, source: str = "<string>") -> Sweep:
    """Parse and validate one sweep file's text; raise :class:`DataError`."""
    meta: dict[str, tuple[int, str]] = {}
    header: list[str] | None = None
    header_line = 0
    rows: list[tuple[int, list[str]]] = []
    lines = text.splitlines()
    for lineno, raw in enumerate(lines, start=1):
        s = raw.strip()
        if not s:
            continue
        if s.startswith("#"):
            if header is not None:
                continue  # comments between data rows are allowed
            m = _META_RE.match(s)
            if m:
                key = m.group(1).lower()
                if key in meta:
                    raise DataError(source, lineno, f"'{key}' given twice (first on line {meta[key][0]})")
                meta[key] = (lineno, m.group(2))
            continue
        if header is None:
            header = [c.strip().lower() for c in next(csv.reader([s]))]
            header_line = lineno
            continue
        rows.append((lineno, next(csv.reader([s]))))

    if "format" not in meta:
        raise DataError(source, 1, f"no '# format = {FORMAT_TAG}' line: not a torqueloop sweep file")
    if meta["format"][1] != FORMAT_TAG:
        raise DataError(source, meta["format"][0], f"format {meta['format'][1]!r} is not {FORMAT_TAG!r}")

    def need(key: str) -> tuple[int, str]:
        if key not in meta:
            raise DataError(source, None, f"missing header line '# {key} = ...'")
        return meta[key]

    def num(key: str) -> float:
        ln, v = need(key)
        return _num(source, ln, key, v)

    kind_line, kind = need("sweep")
    kind = kind.lower()
    if kind not in ("frequency", "duty"):
        raise DataError(source, kind_line, f"sweep = {kind!r}: must be 'frequency' or 'duty'")
    motor = meta.get("motor", (0, ""))[1]

    r = num("wheel_radius_m")
    if r <= 0:
        raise DataError(source, meta["wheel_radius_m"][0], f"wheel_radius_m = {r} must be > 0")
    theta = num("theta_deg")
    if not 0 < theta < 180 or math.sin(math.radians(theta)) < 0.1:
        raise DataError(
            source, meta["theta_deg"][0],
            f"theta_deg = {theta}: the rope must pull across the radius (sin(theta) >= 0.1; 90 = tangent)",
        )
    vs = num("supply_v")
    if vs <= 0:
        raise DataError(source, meta["supply_v"][0], f"supply_v = {vs} must be > 0")
    bench = BenchConstants(r, theta, vs)

    x_name = "freq_hz" if kind == "frequency" else "duty_pct"
    if header is None:
        raise DataError(source, None, f"no column header line (expected {x_name},force_n,current_a)")
    dup = {c for c in header if header.count(c) > 1}
    if dup:
        raise DataError(source, header_line, f"column(s) {sorted(dup)} appear twice")
    missing = [c for c in (x_name, "current_a") if c not in header]
    has_f, has_t = "force_n" in header, "torque_nm" in header
    if not has_f and not has_t:
        missing.append("force_n (or torque_nm)")
    if missing:
        raise DataError(source, header_line, f"missing column(s): {', '.join(missing)}; header is {','.join(header)}")
    if has_f and has_t:
        raise DataError(source, header_line, "give force_n or torque_nm, not both (which one is the measurement?)")
    y_name = "force_n" if has_f else "torque_nm"
    cols = {c: header.index(c) for c in (x_name, y_name, "current_a", "current_std_a") if c in header}

    xs: list[float] = []
    ys: list[float] = []
    cur: list[float] = []
    cstd: list[float] = []
    for lineno, cells in rows:
        if len(cells) != len(header):
            raise DataError(source, lineno, f"{len(cells)} fields, header has {len(header)}")
        vals = {c: _num(source, lineno, c, cells[i]) for c, i in cols.items()}
        x = vals[x_name]
        if kind == "frequency" and x <= 0:
            raise DataError(source, lineno, f"freq_hz = {x} must be > 0")
        if kind == "duty" and not 0 <= x <= 100:
            raise DataError(source, lineno, f"duty_pct = {x} outside 0..100")
        if xs and x <= xs[-1]:
            what = "frequency" if kind == "frequency" else "duty"
            raise DataError(
                source, lineno,
                f"non-monotonic {what}: {x:g} after {xs[-1]:g} (rows must be strictly increasing)",
            )
        if vals[y_name] < 0:
            raise DataError(
                source, lineno,
                f"negative {'force' if has_f else 'torque'} {vals[y_name]:g}: a rope can only pull "
                "(check the meter's zero or the motor's direction)",
            )
        if vals["current_a"] < 0:
            raise DataError(source, lineno, f"negative current {vals['current_a']:g} A (check the probe direction)")
        if "current_std_a" in vals and vals["current_std_a"] < 0:
            raise DataError(source, lineno, f"negative current_std_a {vals['current_std_a']:g}")
        xs.append(x)
        ys.append(vals[y_name])
        cur.append(vals["current_a"])
        if "current_std_a" in vals:
            cstd.append(vals["current_std_a"])

    min_pts = MIN_FREQ_POINTS if kind == "frequency" else MIN_DUTY_POINTS
    if len(xs) < min_pts:
        raise DataError(
            source, None,
            f"{len(xs)} data rows; the {kind} sweep needs at least {min_pts}",
        )

    y = np.array(ys)
    torque = np.asarray(bench.torque_nm(y)) if has_f else y
    kw: dict[str, object] = {}
    if kind == "frequency":
        duty = num("duty_pct")
        if not 0 < duty < 100:
            raise DataError(source, meta["duty_pct"][0], f"duty_pct = {duty} must be between 0 and 100")
        kw["duty_pct"] = duty
        sf, st = "stall_force_n" in meta, "stall_torque_nm" in meta
        if sf == st:
            raise DataError(
                source, None,
                "step 2 needs exactly one of '# stall_force_n = ...' or '# stall_torque_nm = ...' "
                "(the reading at nominal voltage, 100 % on)",
            )
        if sf:
            f = num("stall_force_n")
            if f <= 0:
                raise DataError(source, meta["stall_force_n"][0], f"stall_force_n = {f} must be > 0")
            kw["stall_torque_nm"] = float(bench.torque_nm(f))
        else:
            t = num("stall_torque_nm")
            if t <= 0:
                raise DataError(source, meta["stall_torque_nm"][0], f"stall_torque_nm = {t} must be > 0")
            kw["stall_torque_nm"] = t
        if "stall_current_a" in meta:
            c = num("stall_current_a")
            if c < 0:
                raise DataError(source, meta["stall_current_a"][0], f"stall_current_a = {c} must be >= 0")
            kw["stall_current_a"] = c
    else:
        fhz = num("freq_hz")
        if fhz <= 0:
            raise DataError(source, meta["freq_hz"][0], f"freq_hz = {fhz} must be > 0")
        kw["freq_hz"] = fhz

    return Sweep(
        kind=kind,  # type: ignore[arg-type]
        motor=motor,
        bench=bench,
        x=np.array(xs),
        torque_nm=torque,
        current_a=np.array(cur),
        current_std_a=np.array(cstd) if cstd else None,
        source=source,
        force_given=has_f,
        meta={k: v for k, (_, v) in meta.items()},
        **kw,  # type: ignore[arg-type]
    )


def read_sweep(path: str | Path) -> Sweep:
    p = Path(path)
    try:
        text = p.read_text(encoding="utf-8")
    except UnicodeDecodeError as e:
        raise DataError(str(p), None, f"not UTF-8 text ({e.reason})") from None
    except OSError as e:
        raise DataError(str(p), None, f"cannot read ({e.strerror})") from None
    return parse_sweep(text, source=str(p))


def format_sweep(sw: Sweep, comment: str = "") -> str:
    """The CSV text of a sweep (torque columns when the sweep holds torques
    that did not come from a force, force columns otherwise)."""
    out = io.StringIO()
    if comment:
        for c in comment.splitlines():
            out.write(f"# {c}\n")
    out.write(f"# format = {FORMAT_TAG}\n# sweep = {sw.kind}\n")
    if sw.motor:
        out.write(f"# motor = {sw.motor}\n")
    b = sw.bench
    out.write(f"# wheel_radius_m = {b.wheel_radius_m:.9g}\n# theta_deg = {b.theta_deg:.9g}\n# supply_v = {b.supply_v:.9g}\n")
    k = float(b.torque_nm(1.0))  # torque per newton
    if sw.kind == "frequency":
        out.write(f"# duty_pct = {sw.duty_pct:.9g}\n")
        assert sw.stall_torque_nm is not None
        if sw.force_given:
            out.write(f"# stall_force_n = {sw.stall_torque_nm / k:.9g}\n")
        else:
            out.write(f"# stall_torque_nm = {sw.stall_torque_nm:.9g}\n")
        if sw.stall_current_a is not None:
            out.write(f"# stall_current_a = {sw.stall_current_a:.9g}\n")
    else:
        out.write(f"# freq_hz = {sw.freq_hz:.9g}\n")
    ycol = "force_n" if sw.force_given else "torque_nm"
    cols = [sw.x_name, ycol, "current_a"] + (["current_std_a"] if sw.current_std_a is not None else [])
    out.write(",".join(cols) + "\n")
    y = sw.torque_nm / k if sw.force_given else sw.torque_nm
    for i in range(len(sw.x)):
        row = [f"{sw.x[i]:.9g}", f"{y[i]:.9g}", f"{sw.current_a[i]:.9g}"]
        if sw.current_std_a is not None:
            row.append(f"{sw.current_std_a[i]:.9g}")
        out.write(",".join(row) + "\n")
    return out.getvalue()


def write_sweep(path: str | Path, sw: Sweep, comment: str = "") -> None:
    p = Path(path)
    p.parent.mkdir(parents=True, exist_ok=True)
    p.write_text(format_sweep(sw, comment), encoding="utf-8")
