# SPDX-License-Identifier: MIT
"""The studies' floor: an experiment plan becomes runs that carry parsed
plants (never names), pickle into pool workers, and file into the report;
the study command refuses bad input in one line."""

from __future__ import annotations

import pickle
import subprocess
import sys
from pathlib import Path

import pytest

from sim_models.variants import PlantSpec, plant_of
from torqueloop.sim import report
from torqueloop.study.experiment import CASES, ExperimentPlan, RunFailed, collect, runs


def test_the_quick_plan_is_the_runs_make_run_quick_does() -> None:
    plan = ExperimentPlan.short(experiment_plant=plant_of("lab-no-brush_drop"))
    rs = runs(plan, Path("char.json"))
    kinds = [r.kind for r in rs]
    # 3 laws x (RTL arm, model arm, each case) + 3 carriers x P x PW0 on/off, one start and step
    assert kinds.count("rtl") == 3 and kinds.count("model") == 3
    assert kinds.count("fast") == 3 * len(CASES) + 3 * 2
    assert kinds[:3] == ["rtl"] * 3, "the long runs go first"
    for r in rs:
        assert isinstance(r.config.plant, PlantSpec)
        want = plan.model_plant if r.kind == "model" else plan.experiment_plant
        assert r.config.plant == want, r.label()
        assert (r.config.char_config is None) == (r.kind == "model")
        assert pickle.loads(pickle.dumps(r)) == r          # what the pool sends a worker
    sweep = [r for r in rs if r.key[0] == "sweep"]
    assert {r.config.pwm_hz for r in sweep} == {(f, f) for f in plan.sweep_hz}
    assert all(r.config.t_end_s == plan.sweep_t_end_s for r in sweep)


def test_make_runs_sweep_is_pd_and_pid_at_40_s_each_carrier_with_its_own_dead_zone_from_two_starts() -> None:
    pw0 = {f: (int(f) % 97, int(f) % 89) for f in ExperimentPlan.thorough().sweep_hz}
    rs = [r for r in runs(ExperimentPlan(), Path("char.json"), pw0) if r.key[0] == "sweep"]
    assert len(rs) == 4 * 2 * 2 * 1 * 2       # carriers x laws x PW0 on/off x steps x starts
    for r in rs:
        f, on = r.key[1], r.key[2]
        assert r.config.pw0_off != on and (not on or r.config.pw0_counts == pw0[f])
        assert r.config.t_end_s == 40.0 and r.config.law in ("PD", "PID")
    assert {r.config.start_counts for r in rs} == {(-4200, -4200), (4200, 4200)}
    assert sum(r.key[0] == "sweep" for r in runs(ExperimentPlan.thorough(), Path("c"), pw0)) == 8 * 2 * 2 * 2 * 3


def test_results_are_filed_where_the_report_reads_them() -> None:
    st = report.Study(t_end_s=1.0, target_rad=6.28, laws=["P"])
    plan = ExperimentPlan.short(laws=("P",))
    rs = {r.label(): r for r in runs(plan, Path("c.json"), {f: (30, 8) for f in plan.sweep_hz})}
    collect(st, rs["model P"], "m")
    collect(st, rs["rtl P"], ("e", "f"))
    collect(st, rs["fast case pw0_off P"], "v")
    collect(st, rs["fast sweep 50.0 True P 1.0 0"], "s")
    assert st.model_arm == {"P": "m"} and st.experiment_arm == {"P": "e"} and st.fast_check == {"P": "f"}
    assert st.cases == {"pw0_off": {"P": "v"}} and st.sweep[0][:4] == (50.0, True, "P", "s")
    assert st.sweep[0][4]["x"] == {"pw0_counts": 30, "start_counts": 0, "step_counts": 8400}
    assert isinstance(RunFailed("x"), str)


@pytest.mark.parametrize("argv, says", [
    (["experiment", "--experiment-plant", "lob"], "unknown plant variant 'lob'"),
    (["experiment", "--t-end", "0"], "must be positive"),
    (["characterize", "sim", "--plant", "lab-no-brushes"], "unknown effect 'brushes'"),
    (["nothing"], "unknown study 'nothing'"),
])
def test_bad_input_is_one_line(argv: list[str], says: str) -> None:
    r = subprocess.run([sys.executable, "-m", "torqueloop.study", *argv], capture_output=True, text=True, timeout=120)
    assert r.returncode != 0 and "Traceback" not in r.stderr, r.stderr
    assert len(r.stderr.strip().splitlines()) == 1 and says in r.stderr, r.stderr


def test_banners_go_to_the_log_and_progress_to_the_terminal(tmp_path, capfd) -> None:
    import os

    from torqueloop.study.experiment import _say, banners_to
    with banners_to(tmp_path / "run.log"):
        os.write(1, b"cocotb banner\n")
        os.write(2, b"verilator warning\n")
        _say("1/2 a run (3 s; about 3 s left)")
    out = capfd.readouterr().out
    assert "1/2 a run" in out and "banner" not in out
    assert (tmp_path / "run.log").read_text() == "cocotb banner\nverilator warning\n"
