# SPDX-License-Identifier: MIT
"""The characterisation method on the simulated bench, end to end: both
motors of Table 2 on the plant's dynamometer, pins from the RTL (freq_div +
pwm_torque under Verilator) and, for comparison, from the cores' documented
waveform with the IBT-2's two off-phases.  Prints what the method chooses
and how long the RTL-driven run takes; the sweeps, plots and configuration
stay in build/characterize_bench/."""

from __future__ import annotations

import contextlib
import io
import time
from pathlib import Path

from torqueloop.characterize import load_config
from torqueloop.characterize.cli import EXIT_OK
from torqueloop.characterize.cli import main as characterize
from torqueloop.flow.manifest import REPO_ROOT
from torqueloop.models import freq_div

OUT = REPO_ROOT / "build" / "characterize_bench"


def _run(tag: str, *args: str) -> tuple[int, float, Path]:
    out = OUT / tag
    t0 = time.monotonic()
    log = io.StringIO()
    with contextlib.redirect_stdout(log):
        rc = characterize(["sim", "--out-dir", str(out), *args])
    (OUT / f"{tag}.log").parent.mkdir(parents=True, exist_ok=True)
    (OUT / f"{tag}.log").write_text(log.getvalue())
    return rc, time.monotonic() - t0, out


def _summary(tag: str, rc: int, dt: float, out: Path) -> None:
    print(f"{tag:<22} exit {rc}, {dt:6.1f} s wall")
    if rc != EXIT_OK:
        print(f"  see {OUT / (tag + '.log')}")
        return
    cfg = load_config(out / "characterization.json")
    for name, a in cfg.axes.items():
        first = a.provenance["candidates_tried"][0]
        print(f"  {name}: tau_max {a.tau_max_nm:.4f} N m, chosen {a.pwm_freq_hz:.4f} Hz ({first['kind']}), "
              f"count_max {a.count_max} -> {a.achieved_hz:.4f} Hz ({a.freq_error_pct:+.3f} %), "
              f"PW0 {a.duty_pw0_pct:.3f} % = {a.pw0_counts} counts, PW_F {a.pw_max_counts}, "
              f"R^2 {a.step7['r2']:.6f}, worst dev {100 * a.step7['worst_dev_frac']:.3f} % of tau_max")


def main() -> int:
    print("paper frequencies on the DE0-CV (eq. 4, 50 MHz, 10 bits, 1023-tick period):")
    for f in (450.0, 200.0):
        e = freq_div.frequency_error(f)
        print(f"  {f:g} Hz: Count_max {e.count_max}, pins {e.f_carrier_hz:.4f} Hz ({100 * e.error_carrier:+.3f} %)")
    results = []
    for tag, args in (
        ("rtl_brake", ("--source", "rtl", "--simulator", "verilator")),
        ("model_brake", ("--source", "model")),
        ("model_coast", ("--source", "model", "--drive", "coast")),
    ):
        print(f"[bench_characterize] {tag} ...", flush=True)
        rc, dt, out = _run(tag, *args)
        _summary(tag, rc, dt, out)
        results.append(rc)
    same = all(
        (OUT / "rtl_brake" / "data" / ax / f).read_text().splitlines()[1:]
        == (OUT / "model_brake" / "data" / ax / f).read_text().splitlines()[1:]
        for ax in ("x", "z")
        for f in sorted(p.name for p in (OUT / "rtl_brake" / "data" / ax).glob("*.csv"))
    ) if results[0] == EXIT_OK and results[1] == EXIT_OK else False
    print(f"RTL-driven and model-pin sweeps identical (apart from the comment line): {same}")
    return 0 if all(r == EXIT_OK for r in results) and same else 1


if __name__ == "__main__":
    raise SystemExit(main())
