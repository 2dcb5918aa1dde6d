# SPDX-License-Identifier: MIT
"""What the characterisation chooses on the lab bench when one assumed value
changes (docs/plant.md, "Sensitivity"): the lab's session (instrument seed 0,
the cores' documented pins) for the baseline and for each row's change, the
chosen carrier and PW0 per motor.  The lab variant's friction, brush drop
and gear stages, and the bench's rope, damping and wheel, are assumptions
(no datasheet gives them for this motor); this table says how much each one
moves the method's answer."""

from __future__ import annotations

import tempfile
import time
from dataclasses import replace
from pathlib import Path

from sim_models.dyno import RopeBenchConfig
from sim_models.variants import PlantSpec
from torqueloop.characterize.simbench import LabBench, Waveforms, simulate_lab

B = RopeBenchConfig()
ROWS: list[tuple[str, dict, RopeBenchConfig]] = [
    ("baseline", {}, B),
    ("Coulomb friction 2 % of stall (3 %)", {"motor_friction": {"coulomb_frac": 0.02, "static_frac": 0.028}}, B),
    ("Coulomb friction 4.5 % of stall", {"motor_friction": {"coulomb_frac": 0.045, "static_frac": 0.063}}, B),
    ("breakaway 1.2 x Coulomb (1.4 x)", {"motor_friction": {"coulomb_frac": 0.03, "static_frac": 0.036}}, B),
    ("brush drop 0.25 V (0.5 V)", {"brush_drop": {"volts": 0.25}}, B),
    ("brush drop 1.0 V", {"brush_drop": {"volts": 1.0}}, B),
    ("3 gear stages (5): back-driving 0.949 -> 0.947", {"gear_efficiency": {"stages": 3}}, B),
    ("back-driving efficiency 0.85", {"gear_efficiency": {"stages": 5, "back": 0.85}}, B),
    ("undamped gauge, 150 N s/m (4000)", {}, replace(B, rope_N_s_per_m=150.0, settle_s=1.0)),
    ("stiffer rope, 8.5e5 N/m (1.7e5)", {}, replace(B, rope_N_per_m=8.5e5)),
    ("wheel inertia 1e-3 kg m^2 (2e-4)", {}, replace(B, wheel_inertia_kg_m2=1e-3)),
]


def main() -> int:
    from bench import QUICK

    rows = ROWS[:3] if QUICK else ROWS
    wf = Waveforms("model")
    print("| change (baseline) | x: chosen (Hz) | x: PW0 (%) | z: chosen (Hz) | z: PW0 (%) | wall (s) |")
    print("|---|---|---|---|---|---|")
    with tempfile.TemporaryDirectory() as tmp:
        for k, (label, tweak, cfg) in enumerate(rows):
            t0 = time.monotonic()
            bench = LabBench(PlantSpec("lab"), cfg, tweak)
            res = simulate_lab(Path(tmp) / f"r{k}", bench, seed=0, wf=wf, quiet=True)
            cells = []
            for a in ("x", "z"):
                r = res[a]
                cells += ([f"{r.chosen.freq_hz:.4g}", f"{r.linearity.pw0_pct:.2f}"] if r.status == "pass"
                          else [r.status, "-"])
            print(f"| {label} | " + " | ".join(cells) + f" | {time.monotonic() - t0:.0f} |", flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
