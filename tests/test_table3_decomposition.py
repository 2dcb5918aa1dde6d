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
