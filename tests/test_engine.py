# SPDX-License-Identifier: MIT
"""The study's engines (torqueloop/study/engine.py): the local pool and a
real Dask cluster (a scheduler and two worker processes on 127.0.0.1, as
`dask scheduler` and `dask worker` would run on lab PCs) give the same
results for the same jobs - a pure function, and a short study: sweep points
of the experiment (the firmware's law, the PWM event model and the lab plant,
torqueloop.study.experiment.execute) on both engines, trajectories equal."""

import math

import numpy as np
import pytest

from sim_models.variants import PlantSpec
from torqueloop.sim.experiment import ExperimentConfig
from torqueloop.study.engine import Engine, EngineError
from torqueloop.study.experiment import Run, execute


def _work(n: int) -> float:
    """A job with a result that depends on nothing but its input."""
    return sum(math.sin(k * n) for k in range(20000))


JOBS = list(range(12))


def test_the_local_pool_runs_every_job_once():
    got = dict(Engine(jobs=2).map_unordered(_work, JOBS))
    assert got == {n: _work(n) for n in JOBS}


STUDY = [Run("fast", ("sweep", f, True, law),
              ExperimentConfig(law=law, t_end_s=0.5, plant=PlantSpec("lab"), pwm_hz=(f, f), progress=False))
         for f in (1700.0, 24_400.0) for law in ("P", "PD")]


def _trajectories(pairs) -> dict:
    out = {}
    for run, (_, result, _) in pairs:
        assert not isinstance(result, str), result          # RunFailed is a str
        out[run.key] = (result.traj.t, result.traj.pos, result.traj.cmd)
    return out


def test_a_dask_cluster_gives_what_the_pool_gives():
    distributed = pytest.importorskip("distributed")
    pool = dict(Engine(jobs=2).map_unordered(_work, JOBS))
    study_pool = _trajectories(Engine(jobs=2).map_unordered(execute, STUDY))
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, host="127.0.0.1",
                                  dashboard_address=None) as cluster:
        eng = Engine(address=cluster.scheduler_address)
        assert eng.name.startswith("dask distributed at tcp://127.0.0.1:")
        got = list(eng.map_unordered(_work, JOBS))
        study_dask = _trajectories(eng.map_unordered(execute, STUDY))
        workers = {w for w in cluster.scheduler.workers}
    assert len(workers) == 2
    assert dict(got) == pool and len(got) == len(JOBS)
    assert study_dask.keys() == study_pool.keys() == {r.key for r in STUDY}
    for k in study_pool:
        for a, b in zip(study_pool[k], study_dask[k]):
            assert np.array_equal(a, b), k           # bit for bit: the same inputs, the same run


def test_no_scheduler_is_one_line():
    pytest.importorskip("distributed")
    with pytest.raises(EngineError) as e:
        list(Engine(address="tcp://127.0.0.1:9").map_unordered(_work, JOBS))
    assert "no Dask scheduler answers at tcp://127.0.0.1:9" in str(e.value)


def _schedule(costs: list[float], workers: int, speed: float, rng) -> list[tuple[float, int, float]]:
    """(finish time, run, its seconds) of the runs on ``workers`` taken in order, each as it
    frees; each run's speed off the mean by up to 25 % (its cost is an estimate too)."""
    free = [0.0] * workers
    out = []
    for k, c in enumerate(costs):
        w = min(range(workers), key=free.__getitem__)
        busy = c / (speed * rng.uniform(0.75, 1.25))
        free[w] += busy
        out.append((free[w], k, busy))
    return sorted(out)


@pytest.mark.parametrize("costs", [[1480.0] * 3 + [8.0] * 3 + [40.0] * 9 + [42.0] * 32,   # make run's stage
                                   [5.0, 3.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0]])
def test_progress_estimates_the_time_left_of_runs_of_unequal_cost(monkeypatch, costs):
    """With each run's cost roughly known (each run's speed off by up to 25 %), the estimate
    after each finished run is within half the schedule's true time left, plus a quarter of
    the longest run (what its own speed can move the end); the plain elapsed / k x (n - k)
    read many times the truth after the first long run."""
    import random

    from torqueloop.study import engine as E

    seed = random.randrange(1 << 30)
    print(f"seed {seed}")

    now = [0.0]
    monkeypatch.setattr(E.time, "monotonic", lambda: now[0])
    p = E.Progress(costs, 2)
    sched = _schedule(costs, 2, 0.64, random.Random(seed))
    end = sched[-1][0]
    longest = max(b for _, _, b in sched)
    for k, (t, run, busy) in enumerate(sched[:-1], 1):
        now[0] = t
        left = p.done(costs[run], busy)
        plain = t / k * (len(costs) - k)
        print(f"{k}/{len(costs)}: true {end - t:.0f} s, estimated {left:.0f} s, plain {plain:.0f} s")
        # half the truth, plus what one run's own 25 % can move it (the stage's last long run)
        assert abs(left - (end - t)) <= 0.5 * (end - t) + 0.25 * longest, (k, left, end - t)
    first = sched[0][0]
    assert first / 1 * (len(costs) - 1) > 2 * (end - first), "the plain estimate was not wrong here"


def test_durations_read_as_people_read_them():
    from torqueloop.study.engine import human_s

    assert [human_s(s) for s in (0.4, 45, 89, 95, 720, 5300, 5401, 106722)] == \
        ["0 s", "45 s", "89 s", "2 min", "12 min", "88 min", "1 h 30 min", "29 h 39 min"]
