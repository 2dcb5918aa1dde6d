# SPDX-License-Identifier: MIT
"""The Table 3 analogue decomposed: what each difference between the two
arms contributes to the RMSE between them (eq. 26-27).

The paper's Table 3 has no numbers in its text, so the analogue compares
this project's own two arms; its RMSE measures how far the experiment arm
is from the paper's simulation, and this module says what that distance is
made of.  Each difference is added *alone* to the model arm (the paper's
simulation on the `paper` plant) and the RMSE against the model arm itself
is computed:

* each plant effect of the experiment plant (``paper`` + that effect: the
  variant with every other effect off), the model arm's averaged drive and
  unquantised position kept;
* every plant effect at once (the experiment plant under the model arm);
* ``measured_tau_max``: the scaling of eq. (19) by the tau_max the
  characterisation measured (the experiment arm's file) instead of the
  paper's, on the `paper` plant with the model arm's averaged drive;
* the drive and the controller as the board has them - the PWM carrier,
  the encoder's quantisation and the firmware's fixed-point law with the
  paper's carriers, no PW0 and the paper's tau_max - on the `paper` plant
  (the fast path): these three are one row, because the fast path cannot
  take one without the others;
* ``experiment_arm``: the whole difference, the report's Table 3 analogue.

The effects do not add: the rows show which difference carries the RMSE,
not a partition of it.  Every row is run for each law asked for (``make
run``: P, PD and PID).
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Sequence

from sim_models.variants import PlantSpec, effects_of
from torqueloop.study.engine import Engine, Progress


@dataclass(frozen=True)
class Job:
    law: str
    row: str                 # an effect name, "all_plant_effects", "measured_tau_max", "pwm_encoder_firmware"
    plant: PlantSpec
    t_end_s: float
    char_config: str | None = None   # measured_tau_max: the characterisation file whose tau_max scales the law


def _plant_with_only(base: PlantSpec, effect: str) -> PlantSpec:
    return PlantSpec(base.name, tuple(e for e in effects_of(base.name) if e != effect))


def jobs(experiment_plant: PlantSpec, laws: Sequence[str], t_end_s: float, drive_row: bool = True,
         char_config: str | None = None) -> list[Job]:
    """Every row for every law; ``char_config`` (the experiment arm's
    characterisation file) adds the ``measured_tau_max`` row."""
    out = []
    for law in laws:
        out.append(Job(law, "model_arm", PlantSpec("paper"), t_end_s))
        for e in effects_of(experiment_plant.name):
            out.append(Job(law, e, _plant_with_only(experiment_plant, e), t_end_s))
        out.append(Job(law, "all_plant_effects", experiment_plant, t_end_s))
        if char_config is not None:
            out.append(Job(law, "measured_tau_max", PlantSpec("paper"), t_end_s, char_config))
        if drive_row:
            out.append(Job(law, "pwm_encoder_firmware", PlantSpec("paper"), t_end_s))
    return out


#: the rows' measured CPU at T = 40 s, most first (docs/experiment.md, "Table 3 decomposition, measured"): every
#: effect at once 128-150 s, backlash 68-81 s, gear efficiency 19-29 s, R(T) 8-11 s; the rest 1-6 s
SLOW_ROWS = ("all_plant_effects", "gear_backlash", "gear_efficiency", "winding_thermal")


def longest_first(js: Sequence[Job]) -> list[Job]:
    """The order the engine takes the jobs in: the slow rows first, so no long
    run is left alone on one worker at the end while the other idles."""
    rank = {r: k for k, r in enumerate(SLOW_ROWS)}
    return sorted(js, key=lambda j: rank.get(j.row, len(SLOW_ROWS)))


def run_job(job: Job) -> dict[str, Any]:
    from torqueloop.sim.experiment import ExperimentConfig, run_fast, run_paper_model

    t0 = time.process_time()
    cfg = ExperimentConfig(law=job.law, t_end_s=job.t_end_s, plant=job.plant, progress=False,
                           char_config=job.char_config)
    try:
        r = run_fast(cfg) if job.row == "pwm_encoder_firmware" else run_paper_model(cfg)
        return {"traj": r.traj, "cpu_s": time.process_time() - t0}
    except Exception as e:  # noqa: BLE001 - a row that cannot run says why; the others go on
        return {"error": f"{type(e).__name__}: {e}", "cpu_s": time.process_time() - t0}


def run(experiment_plant: PlantSpec, laws: Sequence[str], t_end_s: float, engine: Engine = Engine(),
        drive_row: bool = True, say=print, char_config: str | None = None) -> dict[str, Any]:
    """``{<row>: {<law>: {rmse_position_rad, rmse_velocity_rad_s} | {error}}}``."""
    from torqueloop.sim.report import compare

    js = jobs(experiment_plant, laws, t_end_s, drive_row, char_config)
    say(f"Table 3 decomposition: {len(js)} runs (each arm difference added alone to the model arm, T = {t_end_s:g} s) "
        f"on the {engine.name}")
    got: dict[tuple[str, str], dict[str, Any]] = {}
    progress = Progress([1.0] * len(js), engine.workers)
    for k, (job, r) in enumerate(engine.map_unordered(run_job, longest_first(js)), 1):
        got[(job.law, job.row)] = r
        say(f"table3 {k}/{len(js)} {job.law} {job.row} ({r['cpu_s']:.0f} s CPU; {progress.line(1.0, r['cpu_s'])})")
    out: dict[str, Any] = {}
    for job in js:
        if job.row == "model_arm":
            continue
        base, r = got[(job.law, "model_arm")], got[(job.law, job.row)]
        if "error" in r or "error" in base:
            cell: dict[str, Any] = {"error": r.get("error") or base.get("error")}
        else:
            c = compare(base["traj"], r["traj"])
            cell = {"rmse_position_rad": c["rmse_position_rad"], "rmse_velocity_rad_s": c["rmse_velocity_rad_s"]}
        out.setdefault(job.row, {})[job.law] = cell | {"cpu_s": r["cpu_s"]}
    return out


def arms_digest(base_digest: str, char_config: str | None) -> str:
    """What the decomposition's runs depend on beyond the plant and the
    method (``base_digest``: characterization.inputs_digest): the two arms'
    code (torqueloop/sim, the firmware law's oracle, the spec) and the
    characterisation file's content."""
    import hashlib

    from torqueloop.spec.repo import REPO_ROOT

    root = REPO_ROOT / "torqueloop"
    files = sorted([*(root / "sim").glob("*.py"), *(root / "oracles").glob("*.py"), *(root / "spec").glob("*.py"),
                    *(root / "spec").glob("*.toml")])
    h = hashlib.sha256(base_digest.encode())
    for f in [*files, *([Path(char_config)] if char_config else [])]:
        h.update(f.name.encode())
        h.update(f.read_bytes())
    return h.hexdigest()


def study(experiment_plant: PlantSpec, laws: Sequence[str], t_end_s: float, out_json: Path, digest: str,
          engine: Engine = Engine(), say=print, char_config: str | None = None) -> dict[str, Any]:
    """:func:`run`, reused from ``out_json`` while the plant, the method, the
    arms' code, the characterisation file, the laws and T are unchanged
    (``digest``: characterization.inputs_digest)."""
    from torqueloop.study.cache import cached

    key = repr((experiment_plant.label, tuple(laws), t_end_s, char_config is not None))

    def compute() -> dict[str, Any]:
        t0 = time.monotonic()
        rows = run(experiment_plant, laws, t_end_s, engine, say=say, char_config=char_config)
        return {"rows": rows, "wall_s": time.monotonic() - t0}

    doc = cached(out_json, arms_digest(digest, char_config), __file__, key, compute,
                 say=lambda m: say(f"Table 3 decomposition: {m}"))
    return doc["rows"]


def add_whole(dec: dict[str, Any], table3: dict[str, Any]) -> dict[str, Any]:
    """The report's own Table 3 analogue as the ``experiment_arm`` row, and
    each row's share of it (position RMSE)."""
    dec = dict(dec)
    dec["experiment_arm"] = {law: {"rmse_position_rad": v["rmse_position_rad"],
                                   "rmse_velocity_rad_s": v["rmse_velocity_rad_s"]} for law, v in table3.items()}
    for row, laws in dec.items():
        for law, cell in laws.items():
            whole = table3.get(law, {}).get("rmse_position_rad")
            if whole and "rmse_position_rad" in cell:
                cell["of_whole_position"] = cell["rmse_position_rad"] / whole
    return dec


def markdown(dec: dict[str, Any]) -> list[str]:
    if not dec:
        return []
    laws = sorted({law for v in dec.values() for law in v}, key=["P", "PD", "PID"].index)
    L = ["## What the Table 3 analogue measures: each arm difference added alone", "",
         "The paper's Table 3 has no numbers in its text; this analogue compares the project's own arms. Each row adds one "
         "difference alone to the model arm (the paper's simulation on the `paper` plant) and gives the position RMSE "
         "(eq. 27, rad) against the model arm, and its fraction of the whole (the experiment arm's row). The rows do "
         "not add up: the effects interact.", "",
         "| difference added alone | " + " | ".join(f"{law}: position RMSE (rad), of the whole" for law in laws) + " |",
         "|---|" + "---|" * len(laws)]
    for row, v in dec.items():
        cells = []
        for law in laws:
            c = v.get(law, {})
            if "error" in c:
                cells.append(f"did not run ({c['error'][:60]})")
            elif "rmse_position_rad" in c:
                frac = c.get("of_whole_position")
                cells.append(_rad(c["rmse_position_rad"]) + ("" if frac is None else f", {100 * frac:.0f} %"))
            else:
                cells.append("-")
        L.append(f"| {row} | " + " | ".join(cells) + " |")
    return L + [""]


def _rad(v: float) -> str:
    """An RMSE as people read it: four decimals, a small one in powers of
    ten rather than as 0.0000, rounding noise (below 1e-9 rad) as 0."""
    if v >= 1e-4:
        return f"{v:.4f}"
    return "0" if v < 1e-9 else f"{v:.1e}"
