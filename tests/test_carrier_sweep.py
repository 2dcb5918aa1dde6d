# SPDX-License-Identifier: MIT
"""The carrier sweep without the confound (torqueloop/study/carrier_sweep.py,
answer.py): one PW0 per carrier, the spread over start positions named for
what it is, a start reached by a move before the step, and the report's
opening that answers in words."""

from __future__ import annotations

import json
import math
from dataclasses import replace

import pytest

from sim_models.variants import PlantSpec
from torqueloop.sim.experiment import COUNTS_PER_REV, ExperimentConfig, run_fast
from torqueloop.study import answer
from torqueloop.study.carrier_sweep import pw0_counts, summarise


def test_one_pw0_for_both_directions_is_the_lower_stop_rounded_up() -> None:
    assert pw0_counts([3.91, 3.52]) == math.ceil(3.52 / 100 * 1023)
    assert pw0_counts([0.0, 0.0]) == 0


def _row(f: float, pw0: bool, start: int, err: float) -> dict:
    return {"freq_hz": f, "pw0": pw0, "law": "PD", "axis": "x", "pw0_counts": 30 if pw0 else 0, "start_counts": start,
            "steady_state_error_counts": err, "copper_loss_J": 1.0}


def test_summary_is_the_range_over_start_positions_not_a_confidence_interval() -> None:
    rows = [_row(50.0, True, s, e) for s, e in ((0, 2.0), (-1024, -6.0), (1024, 3.0))] + [_row(24_400.0, True, 0, 1.0)]
    s = summarise(rows)
    lo = next(r for r in s if r["freq_hz"] == 50.0)
    assert lo["steady_state_error_counts"] == {"median": 3.0, "min": 2.0, "max": 6.0}   # |error|
    assert lo["audible"] and not next(r for r in s if r["freq_hz"] == 24_400.0)["audible"]
    assert "not a confidence interval" in lo["interval"]


def test_the_opening_says_when_the_carrier_cannot_be_ranked_and_when_the_choice_does_not_survive() -> None:
    rows = [_row(50.0, True, s, e) for s, e in ((0, 2.0), (-1024, 6.0), (1024, 3.0))]
    rows += [_row(24_400.0, True, s, e) for s, e in ((0, 1.0), (-1024, 5.0), (1024, 2.5))]
    rep = {"meta": {"experiment_plant": "lab", "sweep_T_s": 10.0},
           "characterization": {"axes": {"x": {"achieved_hz": 1163.7}},
                                "stability_verdict": {"axes": {"x": {"stable": False, "n": 9, "min_hz": 1000.0,
                                                                     "max_hz": 5800.0, "median_hz": 2000.0}}}}}
    text, numbers = answer.paragraph(rep, summarise(rows))
    assert "does not survive" in text and "names none" in text
    assert "cannot rank the carriers" in text and not numbers["sweep"][0]["carrier_decides"]
    json.dumps(numbers)


@pytest.mark.parametrize("found, says", [(0, "none of the 4"), (2, "only 2 of the 4")])
def test_protocols_that_found_no_carrier_are_said_and_the_choice_is_not_named(found: int, says: str) -> None:
    """A stability table whose protocols found no carrier (a 3 s or converged settle on lab), or only some
    of them: the opening says so instead of "no stability table" or a span over the ones that found one."""
    rows = [_row(50.0, True, 0, 2.0), _row(24_400.0, True, 0, 1.0)]
    v = ({"stable": False, "min_hz": None, "max_hz": None, "median_hz": None, "n": 4, "chosen": 0} if not found else
         {"stable": False, "min_hz": 676.0, "max_hz": 994.0, "median_hz": 820.0, "n": 4, "chosen": found,
          "tolerance_factor": 1.25})
    rep = {"meta": {"experiment_plant": "lab", "sweep_T_s": 1.0},
           "characterization": {"axes": {"x": {"achieved_hz": 1163.7}}, "stability_verdict": {"axes": {"x": v}}}}
    text, _ = answer.paragraph(rep, summarise(rows))
    assert says in text and "names none" in text and "no stability table" not in text, text


@pytest.mark.parametrize("chosen_hz, survives", [(1050.0, True), (1286.0, False)])
def test_the_choice_survives_only_if_the_protocols_agree_with_it(chosen_hz: float, survives: bool) -> None:
    """Protocols that agree among themselves (850-1073 Hz) back the characterisation's
    choice only when it lies within their tolerance too (the QUICK run's 1286 Hz does not)."""
    rows = [_row(50.0, True, 0, 2.0), _row(24_400.0, True, 0, 1.0)]
    rep = {"meta": {"experiment_plant": "lab", "sweep_T_s": 1.0},
           "characterization": {"axes": {"x": {"achieved_hz": chosen_hz}},
                                "stability_verdict": {"axes": {"x": {"stable": True, "n": 4, "min_hz": 850.1,
                                                                     "max_hz": 1073.0, "median_hz": 995.5,
                                                                     "tolerance_factor": 1.25}}}}}
    text, _ = answer.paragraph(rep, summarise(rows))
    assert ("survives the bench protocols" in text) == survives, text
    assert ("depends on the bench protocol" in text) == (not survives), text


def test_a_start_away_from_zero_is_reached_first_and_the_step_is_measured_from_it() -> None:
    """The paper's plant (no friction): the move to the start lands there, the
    step's trajectory starts at 0 relative to it, and its copper loss counts
    from the step."""
    c = ExperimentConfig(law="PD", t_end_s=0.1, plant=PlantSpec("paper"), pwm_hz=(1700.0, 1700.0), progress=False)
    r = run_fast(replace(c, start_counts=(300, -300), start_s=5.0))
    assert abs(r.traj.pos[0] * COUNTS_PER_REV / (2 * math.pi)).max() < 5
    assert (r.traj.i2[0] == 0).all() and (r.traj.i2[-1] > 0).all()
    assert r.traj.err[0] == __import__("pytest").approx(c.target_counts * 2 * math.pi / COUNTS_PER_REV, abs=0.02)


def test_the_report_opens_with_the_answer_a_quick_banner_and_embeds_every_figure(tmp_path) -> None:
    rows = [_row(f, on, s, e) for f in (50.0, 24_400.0) for on in (True, False) for s, e in ((0, 2.0), (4200, 9.0))]
    rep = {"meta": {"experiment_plant": "lab", "sweep_T_s": 1.0}, "characterization": {}, "sweep": rows}
    (tmp_path / "report.json").write_text(json.dumps(rep))
    (tmp_path / "report.md").write_text("# title\n\nintro\n## the rest\n")
    stab = {"rows": [], "verdict": {}}
    answer.finish(tmp_path, {"T": 2, "n": 2, "laws": "P", "Ts": 1, "nf": 3, "np": 4}, stab, rows, {"rows": []})
    md = (tmp_path / "report.md").read_text()
    assert md.index("QUICK RUN") < md.index("The answer on this model") < md.index("## the rest")
    assert "![" in md and "(carrier_sweep.png)" in md and (tmp_path / "carrier_sweep.png").exists()
    out = json.loads((tmp_path / "report.json").read_text())
    assert out["answer"]["quick"] and out["carrier_sweep"]["rows"][0]["points"] == 2
