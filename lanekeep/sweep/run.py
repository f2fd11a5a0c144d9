"""Running sweep cells: one episode per cell, in local worker processes or as Ray tasks.

Both runners call the same `run_cell` and hand each result to `on_result` as it comes back,
in whatever order the cells finish, so that the caller writes it down at once: a sweep stopped
part-way keeps every finished cell (lanekeep/sweep/store.py) and a resume runs the rest.
A cell that raises comes back as a result with status "failed" and the error, never as an
exception: one bad cell of a thousand must not end the sweep.
"""

from __future__ import annotations

import os
import time
from collections.abc import Callable
from concurrent.futures import FIRST_COMPLETED, wait
from contextlib import contextmanager
from dataclasses import dataclass

from lanekeep.core.reproducibility import kernel_env
from lanekeep.core.workers import THREADS_ENV, worker_pool
from lanekeep.sweep.spec import Cell

OnResult = Callable[["CellResult"], None]
# Statuses of a cell that ran: an episode's own (lanekeep/scoring/metrics.py STATUSES), or "failed"
# (it raised). Resuming skips FINISHED cells and runs the others again.
FINISHED = ("completed", "off_road", "unstable", "collision")


@dataclass(frozen=True)
class CellResult:
    cell_id: str
    status: str  # an episode status (FINISHED or "interrupted") or "failed"
    report: dict | None  # EpisodeReport.to_dict() (judged), None when the cell raised
    error: str  # "ExceptionType: message" on one line when it raised, else ""
    wall_s: float


def run_cell(cell_id: str, table: dict, source: str, seconds: float | None,
             nominal_seed: int) -> CellResult:
    """One episode of a cell, judged by its criteria; whatever it raises becomes "failed".
    Runs in a worker process or Ray task, so it imports what it needs. `nominal_seed`: the
    base file's own seed (lanekeep/sweep/spec.py `Cell.nominal_seed`)."""
    start = time.perf_counter()
    try:
        import lanekeep  # noqa: F401 - MUJOCO_GL before mujoco
        from lanekeep.loop.checks import check_scenario
        from lanekeep.loop.episode import Episode
        from lanekeep.loop.paper_mode import with_mode
        from lanekeep.scoring import criteria
        from lanekeep.sweep.spec import cell_scenario

        scenario = with_mode(cell_scenario(table, source, nominal_seed), None)
        check_scenario(scenario, seconds)
        judged_by = criteria.for_run(scenario.criteria, None,
                                     seconds is None or seconds >= scenario.duration_s)
        with Episode(scenario) as episode:
            report = criteria.judge(episode.run(seconds), judged_by)
        return CellResult(cell_id, report.status, report.to_dict(), "",
                          time.perf_counter() - start)
    except Exception as err:  # noqa: BLE001 - recorded as the cell's failure
        message = " ".join(f"{type(err).__name__}: {err}".split())
        return CellResult(cell_id, "failed", None, message, time.perf_counter() - start)


def run_local(cells: list[Cell], source: str, seconds: float | None, workers: int,
              on_result: OnResult) -> None:
    """The cells in `workers` spawned processes (spawn: EGL and MuJoCo state never forked)."""
    pool = worker_pool(workers)
    try:
        futures = {pool.submit(run_cell, c.cell_id, c.table, source, seconds,
                               c.nominal_seed): c for c in cells}
        pending = set(futures)
        while pending:
            finished, pending = wait(pending, timeout=0.5, return_when=FIRST_COMPLETED)
            for future in finished:
                on_result(_result_of(future, futures[future]))
    except BaseException:
        pool.shutdown(wait=False, cancel_futures=True)
        from lanekeep.core.interrupts import end_children

        end_children(10.0)
        raise
    pool.shutdown(wait=True)


def _result_of(future, cell: Cell) -> CellResult:
    """A future's result; a worker that died (killed, out of memory) fails its cell."""
    try:
        return future.result()
    except Exception as err:  # noqa: BLE001 - BrokenProcessPool and the like
        return CellResult(cell.cell_id, "failed", None,
                          " ".join(f"{type(err).__name__}: {err}".split()), 0.0)


def ray_missing() -> str | None:
    """Why `--ray` cannot run here (None when it can)."""
    try:
        import ray  # noqa: F401
    except ImportError:
        return "--ray needs Ray: pip install 'lanekeep[ray]'"
    return None


def run_ray(cells: list[Cell], source: str, seconds: float | None, on_result: OnResult,
            address: str | None = None, num_cpus: int | None = None) -> None:
    """Each cell a Ray task of one CPU (one episode), results taken as they finish
    (`ray.wait`). `address`: a cluster's ("HOST:6379" or "auto"); None starts a local Ray
    with `num_cpus` CPUs (None: all). Every node needs lanekeep installed."""
    import ray

    with ray_session(address, num_cpus):
        task = ray.remote(num_cpus=1, max_retries=0)(_ray_cell)
        refs: dict = {}
        try:
            refs = {task.remote(c.cell_id, c.table, source, seconds, c.nominal_seed): c
                    for c in cells}
            pending = list(refs)
            while pending:
                done, pending = ray.wait(pending, num_returns=1, timeout=0.5)
                for ref in done:
                    try:
                        result = ray.get(ref)
                    except Exception as err:  # noqa: BLE001 - a task whose worker died
                        result = CellResult(refs[ref].cell_id, "failed", None,
                                            " ".join(f"{type(err).__name__}: {err}".split()
                                                     )[:500], 0.0)
                    on_result(result)
        except BaseException:
            for ref in refs:
                ray.cancel(ref, force=True)
            raise


@contextmanager
def ray_session(address: str | None = None, num_cpus: int | None = None):
    """Ray connected for what runs inside (one start for many `run_ray` calls, e.g. the
    batches of a search); a Ray already connected is used and left as it is."""
    import ray

    # Workers on other nodes do not inherit this process's environment: the kernel pins go
    # with them (lanekeep/core/reproducibility.py), so that every node computes alike.
    env = {"env_vars": {"LP_NUM_THREADS": "1", THREADS_ENV: "1",
                        "MUJOCO_GL": os.environ.get("MUJOCO_GL", "egl"), **kernel_env()}}
    started = not ray.is_initialized()
    if started:
        kwargs = {"address": address} if address else {"num_cpus": num_cpus}
        ray.init(runtime_env=env, include_dashboard=False, log_to_driver=False,
                 configure_logging=False, **kwargs)
    try:
        yield
    finally:
        if started:
            ray.shutdown()


def _ray_cell(cell_id: str, table: dict, source: str, seconds: float | None,
              nominal_seed: int) -> CellResult:
    import cv2

    cv2.setNumThreads(1)
    return run_cell(cell_id, table, source, seconds, nominal_seed)
