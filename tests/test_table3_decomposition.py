# SPDX-License-Identifier: MIT
"""The Table 3 decomposition (torqueloop/study/table3.py): each difference
added alone to the model arm, its RMSE against the model arm, and its share
of the whole."""

from __future__ import annotations

from sim_models.variants import PlantSpec, effects_of
from torqueloop.study import table3
from torqueloop.study.engine import Engine


def test_each_effect_row_is_the_plant_with_only_that_effect() -> None:
    js = table3.jobs(PlantSpec("lab"), ("P",), 1.0)
    rows = {j.row: j for j in js}
    assert set(rows) == {"model_arm", *effects_of("lab"), "all_plant_effects", "pwm_encoder_firmware"}
    for e in effects_of("lab"):
        assert set(rows[e].plant.off) == set(effects_of("lab")) - {e}
    assert rows["all_plant_effects"].plant == PlantSpec("lab") and rows["model_arm"].plant == PlantSpec("paper")


def test_a_difference_that_changes_the_plant_shows_and_the_whole_takes_its_share() -> None:
    """k_e = k_t alone moves the step (a nonzero RMSE); the lab plant with every
    effect switched off is the paper plant, so a row of it reads 0."""
    dec = table3.run(PlantSpec("lab"), ("P",), 0.5, Engine(1), drive_row=False, say=lambda m: None)
    assert dec["energy_consistent"]["P"]["rmse_position_rad"] > 0
    nothing = table3.run_job(table3.Job("P", "x", PlantSpec("lab", tuple(effects_of("lab"))), 0.5))
    base = table3.run_job(table3.Job("P", "model_arm", PlantSpec("paper"), 0.5))
    assert (nothing["traj"].pos == base["traj"].pos).all()
    whole = table3.add_whole(dec, {"P": {"rmse_position_rad": 0.2, "rmse_velocity_rad_s": 1.0}})
    assert whole["experiment_arm"]["P"]["of_whole_position"] == 1.0
    assert "| energy_consistent |" in "\n".join(table3.markdown(whole))


def test_the_gear_efficiency_row_finishes_and_moves_the_step_by_little() -> None:
    """Gear efficiency alone (a rotor without friction of its own, held at
    rest only by the gearbox's band (1 - xi_b) |T_g| / G) once switched the
    rotor's mode about 90 times per control sample on axis x under P once the
    step had settled (from 7.5 s on), most of the row's CPU.  Its RMSE against
    the model arm must stay small: xi_b differs from xi by 0.05 %."""
    import math

    import numpy as np

    from sim_models.stepper import TwoAxisPlant
    from torqueloop.sim.experiment import COUNTS_PER_REV, ExperimentConfig
    from torqueloop.sim.model_loop import TABLE1, LoopConfig, run_averaged
    from torqueloop.sim.report import compare

    t_end = 10.0
    job = table3.Job("P", "gear_efficiency", table3._plant_with_only(PlantSpec("lab"), "gear_efficiency"), t_end)
    params = job.plant.params()
    assert params.axes[0].gear_efficiency_back is not None and params.axes[0].motor_static_N_m == 0.0
    plant = TwoAxisPlant(params, seed=0)
    cfg = ExperimentConfig(law="P", t_end_s=t_end, plant=job.plant)      # the row's own run, with its plant kept
    lc = LoopConfig(setpoint_rad=cfg.target_counts * 2 * math.pi / COUNTS_PER_REV, t_end_s=t_end,
                    sample_s=cfg.period_us * 1e-6, gains=TABLE1["P"])
    r = run_averaged(lc, params, plant)
    samples = len(r.t)
    events = [a.events for a in plant.axes]
    print(f"gear efficiency alone, P, T = {t_end:g} s: {events} mode switches in {samples} samples")
    assert max(events) < 5 * samples, events       # 9815 on x before the fix, about 100 after
    got = table3.run_job(job)
    base = table3.run_job(table3.Job("P", "model_arm", PlantSpec("paper"), t_end))
    assert "error" not in got
    c = compare(base["traj"], got["traj"])
    assert 0.0 < c["rmse_position_rad"] < 1e-3, c
    assert np.array_equal(got["traj"].pos[-1], r.x_meas[-1])    # the same run as the row's


def _char_file(tmp_path, tau_max_nm: dict[str, float]):
    """A characterisation file as the study writes it, with the given tau_max per axis."""
    import json

    from torqueloop.spec.pwm import carrier_hz, divider_for

    axes = {}
    for name, f in (("x", 1000.0), ("z", 250.0)):
        cm = divider_for(f)
        axes[name] = {"motor": name, "pwm_freq_hz": carrier_hz(cm), "count_max": cm, "achieved_hz": carrier_hz(cm),
                      "freq_error_pct": 0.0, "pw0_counts": 10, "pw_max_counts": 1000, "tau_max_nm": tau_max_nm[name],
                      "duty_pw0_pct": 1.0, "duty_pwf_pct": 97.75, "torque_per_count_nm": 0.0024,
                      "step7": {}, "provenance": {}}
    p = tmp_path / f"characterization-{tau_max_nm['x']}.json"
    p.write_text(json.dumps({"schema": "torqueloop-characterization", "schema_version": 1,
                             "clk_hz": 50_000_000, "pwm_bits": 10, "axes": axes, "provenance": {}}))
    return str(p)


def test_the_measured_tau_max_row_changes_only_the_scaling(tmp_path) -> None:
    """The row takes the file's tau_max into eq. (19) on the paper plant: the
    paper's own values read 0; a smaller measured tau_max (a stronger law,
    u = tau / tau_max) moves the step."""
    paper = {a.name: a.tau_max_paper_N_m for a in PlantSpec("paper").params().axes}
    js = table3.jobs(PlantSpec("lab"), ("PD",), 1.0, drive_row=False, char_config=_char_file(tmp_path, paper))
    row = [j for j in js if j.row == "measured_tau_max"]
    assert len(row) == 1 and row[0].plant == PlantSpec("paper")
    assert "measured_tau_max" not in {j.row for j in table3.jobs(PlantSpec("lab"), ("PD",), 1.0)}
    base = table3.run_job(table3.Job("PD", "model_arm", PlantSpec("paper"), 1.0))
    same = table3.run_job(row[0])
    assert (same["traj"].pos == base["traj"].pos).all()
    lower = _char_file(tmp_path, {k: 0.7 * v for k, v in paper.items()})
    moved = table3.run_job(table3.Job("PD", "measured_tau_max", PlantSpec("paper"), 1.0, lower))
    # the same error asks for more duty: saturated for longer, further along the step after 1 s
    assert (abs(moved["traj"].cmd) >= 1023).sum() > (abs(base["traj"].cmd) >= 1023).sum()
    assert (moved["traj"].pos[-1] > base["traj"].pos[-1]).all()


def test_the_decomposition_is_reused_while_its_inputs_are_unchanged(tmp_path, monkeypatch) -> None:
    """make run keeps the table in build/characterize/ and recomputes it when
    the characterisation file (its tau_max) or the laws change."""
    calls = []

    def fake_run(plant, laws, t_end_s, engine, say=print, char_config=None):
        calls.append((tuple(laws), char_config))
        return {"energy_consistent": {law: {"rmse_position_rad": 0.1 * len(calls)} for law in laws}}

    monkeypatch.setattr(table3, "run", fake_run)
    paper = {a.name: a.tau_max_paper_N_m for a in PlantSpec("paper").params().axes}
    char = _char_file(tmp_path, paper)
    out = tmp_path / "dec.json"
    said: list[str] = []
    first = table3.study(PlantSpec("lab"), ("P",), 40.0, out, "digest", say=said.append, char_config=char)
    again = table3.study(PlantSpec("lab"), ("P",), 40.0, out, "digest", say=said.append, char_config=char)
    assert first == again and len(calls) == 1 and any("reused" in m for m in said)
    table3.study(PlantSpec("lab"), ("P", "PD"), 40.0, out, "digest", say=said.append, char_config=char)
    assert len(calls) == 2
    other = _char_file(tmp_path, {k: 0.9 * v for k, v in paper.items()})
    table3.study(PlantSpec("lab"), ("P", "PD"), 40.0, out, "digest", say=said.append, char_config=other)
    assert len(calls) == 3
    table3.study(PlantSpec("lab"), ("P", "PD"), 40.0, out, "another digest", say=said.append, char_config=other)
    assert len(calls) == 4


def test_the_slow_rows_are_handed_out_first_and_every_row_still_runs() -> None:
    js = table3.jobs(PlantSpec("lab"), ("P", "PD", "PID"), 40.0)
    order = table3.longest_first(js)
    assert sorted(map(repr, order)) == sorted(map(repr, js))
    assert [j.row for j in order[:3]] == ["all_plant_effects"] * 3
    assert [j.row for j in order[3:6]] == ["gear_backlash"] * 3
