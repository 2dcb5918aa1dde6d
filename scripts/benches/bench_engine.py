# SPDX-License-Identifier: MIT
"""The study's two engines (torqueloop/study/engine.py) on the same small
work: sweep runs of the experiment's fast path (the lab plant, P and PD at
1.7 and 24.4 kHz, T = 1 s; QUICK: 0.3 s) through the local pool of two
processes and through a Dask cluster of two worker processes started here
on 127.0.0.1 (a real scheduler, as `dask scheduler` / `dask worker` would
run on lab PCs): the wall time of each (the cluster's start-up apart) and
whether the results are identical."""

from __future__ import annotations

import time

import numpy as np

from sim_models.variants import PlantSpec
from torqueloop.sim.experiment import ExperimentConfig
from torqueloop.study.engine import Engine
from torqueloop.study.experiment import Run, execute


def _study(t_end: float) -> list[Run]:
    return [Run("fast", ("sweep", f, True, law),
                ExperimentConfig(law=law, t_end_s=t_end, plant=PlantSpec("lab"), pwm_hz=(f, f), progress=False))
            for f in (1700.0, 24_400.0) for law in ("P", "PD")]


def _run(engine: Engine, jobs: list[Run]) -> tuple[float, dict]:
    t0 = time.monotonic()
    out = {}
    for run, (_, result, _) in engine.map_unordered(execute, jobs):
        if isinstance(result, str):                       # RunFailed
            raise RuntimeError(f"{run.label()}: {result}")
        out[run.key] = (result.traj.pos, result.traj.cmd, result.traj.charge)
    return time.monotonic() - t0, out


def main() -> int:
    from bench import QUICK

    try:
        import distributed
    except ImportError:
        print("Dask distributed is not installed (pip install '.[cluster]'): only the local pool exists")
        return 1
    jobs = _study(0.3 if QUICK else 1.0)
    pool_s, pool = _run(Engine(jobs=2), jobs)
    t0 = time.monotonic()
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, host="127.0.0.1",
                                  dashboard_address=None) as cluster:
        start_s = time.monotonic() - t0
        dask_s, dask = _run(Engine(address=cluster.scheduler_address), jobs)
    same = pool.keys() == dask.keys() and all(np.array_equal(a, b) for k in pool for a, b in zip(pool[k], dask[k]))
    print(f"{len(jobs)} fast-path runs, T = {jobs[0].config.t_end_s:g} s, 2 processes each way")
    print("| engine | wall (s) |")
    print("|---|---|")
    print(f"| local pool | {pool_s:.1f} |")
    print(f"| Dask, 2 workers on 127.0.0.1 | {dask_s:.1f} (+ {start_s:.1f} to start the cluster) |")
    print(f"results identical: {'yes' if same else 'NO'}")
    return 0 if same else 1


if __name__ == "__main__":
    raise SystemExit(main())
