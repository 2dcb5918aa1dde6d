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
