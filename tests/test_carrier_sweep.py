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
from torqueloop.study import carrier_sweep
from torqueloop.study.carrier_sweep import RunCache, pw0_counts, summarise, t_check, truncated
from torqueloop.study.experiment import ExperimentPlan, runs, split_cached


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
    short = [r | {"steady_state_error_counts": 3 * r["steady_state_error_counts"]} for r in rows]
    answer.finish(tmp_path, {"T": 2, "n": 2, "laws": "P", "Ts": 1, "nf": 3, "np": 4}, stab, rows, {"rows": []},
                  t_check=t_check(rows, short, 1.0, 0.5))
    md = (tmp_path / "report.md").read_text()
    assert md.index("QUICK RUN") < md.index("The answer on this model") < md.index("## the rest")
    assert md.index("## The title question") < md.index("### Does the sweep's T change its answer?") < md.index("## the rest")
    assert "![" in md and "(carrier_sweep.png)" in md and (tmp_path / "carrier_sweep.png").exists()
    out = json.loads((tmp_path / "report.json").read_text())
    assert out["answer"]["quick"] and out["carrier_sweep"]["rows"][0]["points"] == 2
    assert all(r["same_ranking"] for r in out["carrier_sweep"]["t_check"]["rows"])


def test_a_runs_first_seconds_are_the_shorter_run() -> None:
    """What lets the sweep be scored at T = 10 s from its 40 s runs: the fast
    path is deterministic, so cutting a run gives the shorter run sample for sample."""
    c = ExperimentConfig(law="PD", t_end_s=0.2, plant=PlantSpec("lab"), pwm_hz=(1700.0, 1700.0), progress=False,
                         start_counts=(200, -200), start_s=0.1)
    short, long = run_fast(c), run_fast(replace(c, t_end_s=0.4))
    cut = truncated(long, 0.2)
    for f in ("t", "pos", "vel", "cmd", "err", "true_pos", "charge", "i2"):
        assert (getattr(cut.traj, f) == getattr(short.traj, f)).all(), f
    assert len(long.traj.t) > len(cut.traj.t)


def test_the_run_cache_keys_on_what_the_run_uses_and_gives_back_what_was_stored(tmp_path) -> None:
    cache = RunCache(tmp_path / "runs")
    c = ExperimentConfig(law="PD", t_end_s=40.0, plant=PlantSpec("lab"), pwm_hz=(50.0, 50.0), pw0_counts=(24, 32),
                         progress=False)
    assert cache.get(c) is None
    cache.put(c, {"result": 1})
    assert cache.get(c) == {"result": 1}
    assert cache.get(replace(c, progress=True)) == {"result": 1}          # progress changes nothing a run computes
    for other in (replace(c, pw0_counts=(25, 32)), replace(c, t_end_s=10.0), replace(c, law="PID"),
                  replace(c, start_counts=(4200, 4200)), replace(c, plant=PlantSpec("lab-2025")),
                  replace(c, pwm_hz=(300.0, 300.0))):
        assert cache.get(other) is None, other
    cache.digest = "another plant or firmware law"
    assert cache.get(c) is None


def test_cached_sweep_runs_are_not_run_again_and_nothing_else_is_taken_from_the_cache(tmp_path) -> None:
    from test_table3_decomposition import _char_file

    plan = ExperimentPlan.short()
    every = runs(plan, _char_file(tmp_path, {"x": 2.0, "z": 2.5}), {f: (30, 8) for f in plan.sweep_hz})
    cache = RunCache(tmp_path / "runs")
    for j in every:
        cache.put(j.config, "stored")        # even an arm's configuration: only sweep runs are reused
    todo, reused = split_cached(every, cache)
    assert {j.label() for j, _ in reused} == {j.label() for j in every if j.key[0] == "sweep"}
    assert all(r == "stored" for _, r in reused)
    assert len(todo) + len(reused) == len(every) and all(j.key[0] != "sweep" for j in todo)


def _err(f: float, pw0: bool, e: float) -> dict:
    return _row(f, pw0, 0, e) | {"law": "PID"}


def test_t_check_says_when_the_shorter_t_ranks_the_carriers_otherwise() -> None:
    long = [_err(50.0, True, 2.0), _err(24_400.0, True, 5.0), _err(50.0, False, 9.0), _err(24_400.0, False, 30.0)]
    same = [_err(50.0, True, 20.0), _err(24_400.0, True, 40.0), _err(50.0, False, 90.0), _err(24_400.0, False, 99.0)]
    flip = [_err(50.0, True, 20.0), _err(24_400.0, True, 4.0), _err(50.0, False, 90.0), _err(24_400.0, False, 99.0)]
    tc = t_check(long, same, 40.0, 10.0)
    assert [r["same_ranking"] for r in tc["rows"]] == [True, True]
    tc = t_check(long, flip, 40.0, 10.0)
    on = next(r for r in tc["rows"] if r["pw0"])
    assert not on["same_ranking"] and on["best_hz_short"] == [24_400.0] and on["best_hz_long"] == [50.0]
    assert on["best_moved"]
    tie = t_check([_err(50.0, True, 0.0), _err(24_400.0, True, 0.0)],
                  [_err(50.0, True, 175.5), _err(24_400.0, True, 157.1)], 40.0, 10.0)["rows"][0]
    assert tie["same_ranking"] and not tie["best_moved"] and tie["best_hz_long"] == [50.0, 24_400.0]
    md = "\n".join(carrier_sweep.t_check_markdown(tc))
    assert "| PID | x | at the carrier | 20.0 -> 2.0 | 4.0 -> 5.0 | 24.4 kHz -> 50 Hz | no |" in md, md


def test_the_opening_says_whether_a_shorter_t_would_have_given_the_same_answer() -> None:
    long = [_err(50.0, True, 2.0), _err(24_400.0, True, 5.0)]
    rep = {"meta": {"experiment_plant": "lab", "sweep_T_s": 40.0}, "characterization": {}}
    same = answer.paragraph(rep, summarise(long), t_check(long, [_err(50.0, True, 9.0), _err(24_400.0, True, 12.0)],
                                                          40.0, 10.0))[0]
    assert "rank in the same order under every law and axis" in same
    text, numbers = answer.paragraph(rep, summarise(long), t_check(long, [_err(50.0, True, 9.0),
                                                                          _err(24_400.0, True, 3.0)], 40.0, 10.0))
    assert "differently for PID axis x" in text and "24.4 kHz at 10 s, 50 Hz at 40 s" in text
    assert "would not have given this answer" in text and numbers["t_check"]["ranking_differs"] == ["PID axis x"]


def test_the_opening_gives_the_error_at_the_screw_and_at_the_inaudible_carrier() -> None:
    rows = [_row(f, True, 0, e) | {"screw_steady_state_error_counts": s}
            for f, e, s in ((50.0, 2.0, 14.0), (1700.0, 30.0, 41.0), (24_400.0, 9.0, 20.0))]
    text = answer.paragraph({"meta": {"experiment_plant": "lab", "sweep_T_s": 40.0}, "characterization": {}},
                            summarise(rows))[0]
    assert "at the screw, beyond the gear's backlash that the motor-side encoder cannot see, 14.0 against 41.0" in text
    assert "at 24.4 kHz, above the audible band, 9.0" in text


def test_carriers_less_than_one_count_apart_are_not_ranked_even_when_the_starts_agree() -> None:
    rep = {"meta": {"experiment_plant": "lab", "sweep_T_s": 40.0}, "characterization": {}}
    close = [_row(50.0, True, s, 2.0) for s in (0, 4200)] + [_row(24_400.0, True, s, 1.2) for s in (0, 4200)]
    text, numbers = answer.paragraph(rep, summarise(close))
    assert "cannot rank the carriers" in text and not numbers["sweep"][0]["carrier_decides"]
    apart = [_row(50.0, True, s, 2.0) for s in (0, 4200)] + [_row(24_400.0, True, s, 0.5) for s in (0, 4200)]
    text, numbers = answer.paragraph(rep, summarise(apart))
    assert "(1.5 against up to 0.0 counts)." in text and numbers["sweep"][0]["carrier_decides"]
