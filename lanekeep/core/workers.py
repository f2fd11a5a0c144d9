"""Worker processes for episodes: how many threads each may use, and the set-up every worker
runs first. One definition for `bench`, `perf`, `sweep` and the tools' pools.

Episodes run in spawned processes (EGL contexts and MuJoCo state do not survive a fork).
Mesa's llvmpipe rasterises with one thread per core and OpenCV and torch parallelise per call;
with two workers on two cores each would start two threads and the workers would fight over
the cores, so each worker's thread counts are set before any of them starts.
"""

from __future__ import annotations

import multiprocessing
import os
from collections.abc import Iterator
from concurrent.futures import ProcessPoolExecutor
from contextlib import contextmanager
from multiprocessing.context import SpawnContext

from lanekeep.core.interrupts import ignore_stop_signals


def worker_threads(workers: int) -> int:
    """Threads each of `workers` processes may use so that together they fill the machine
    once."""
    return max(1, (os.cpu_count() or 1) // max(workers, 1))


# This process's share of the cores, for lanekeep's own threads (an episode runs its detectors
# on two threads when it may use two cores: lanekeep/driver/detection.py). Unset: every core.
THREADS_ENV = "LANEKEEP_THREADS"


def process_threads() -> int:
    """How many threads this process may keep busy: LANEKEEP_THREADS (set for each worker by
    `set_thread_counts`, or by a user) or else the machine's cores."""
    value = os.environ.get(THREADS_ENV, "").strip()
    if value.isdigit() and int(value) > 0:
        return int(value)
    return os.cpu_count() or 1


_RUNNING = None  # in a bench worker: the pool's count of episodes running now (a shared Value)


def threads_now() -> int:
    """How many threads an episode starting a step may keep busy: in a bench worker the cores
    shared among the episodes running now (so the last episode of a bench, alone, gets both
    cores instead of leaving one idle), elsewhere `process_threads()`."""
    if _RUNNING is None:
        return process_threads()
    return max(1, (os.cpu_count() or 1) // max(1, _RUNNING.value))


@contextmanager
def episode_running() -> Iterator[None]:
    """Counts an episode as running in the pool's shared count (a no-op outside a bench)."""
    if _RUNNING is None:
        yield
        return
    with _RUNNING.get_lock():
        _RUNNING.value += 1
    try:
        yield
    finally:
        with _RUNNING.get_lock():
            _RUNNING.value -= 1


def set_thread_counts(threads: int) -> None:
    """Thread counts of the renderer, torch, OpenCV and lanekeep's own; before EGL starts or
    torch is imported (both read the environment once)."""
    os.environ[THREADS_ENV] = str(threads)
    os.environ["LP_NUM_THREADS"] = str(threads)  # Mesa llvmpipe, read when EGL starts
    os.environ["OMP_NUM_THREADS"] = str(threads)  # torch (LaneNet), read at its import
    os.environ.setdefault("MUJOCO_GL", "egl")
    import cv2

    cv2.setNumThreads(threads)


def init_worker(threads: int, running=None) -> None:
    """Runs first in every worker: its thread counts, stop signals left to the parent (an
    idle worker that died of Ctrl-C would break the pool for all), and the pool's shared count
    of running episodes (`threads_now`), if it keeps one."""
    global _RUNNING
    ignore_stop_signals()
    set_thread_counts(threads)
    _RUNNING = running


def spawn_context() -> SpawnContext:
    return multiprocessing.get_context("spawn")


def worker_pool(workers: int, initializer=init_worker, initargs: tuple | None = None
                ) -> ProcessPoolExecutor:
    """`workers` spawned processes, each set up by `initializer` (default: `init_worker` with
    its share of the cores)."""
    args = (worker_threads(workers),) if initargs is None else initargs
    return ProcessPoolExecutor(max_workers=workers, mp_context=spawn_context(),
                               initializer=initializer, initargs=args)
