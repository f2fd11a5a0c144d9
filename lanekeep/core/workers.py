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
from concurrent.futures import ProcessPoolExecutor
from multiprocessing.context import SpawnContext

from lanekeep.core.interrupts import ignore_stop_signals


def worker_threads(workers: int) -> int:
    """Threads each of `workers` processes may use so that together they fill the machine
    once."""
    return max(1, (os.cpu_count() or 1) // max(workers, 1))


# This process's share of the cores, for lanekeep's own threads (an episode runs its detectors
# on two threads when it may use two cores: lanekeep/loop/detection.py). Unset: every core.
THREADS_ENV = "LANEKEEP_THREADS"


def process_threads() -> int:
    """How many threads this process may keep busy: LANEKEEP_THREADS (set for each worker by
    `set_thread_counts`, or by a user) or else the machine's cores."""
    value = os.environ.get(THREADS_ENV, "").strip()
    if value.isdigit() and int(value) > 0:
        return int(value)
    return os.cpu_count() or 1


def set_thread_counts(threads: int) -> None:
    """Thread counts of the renderer, torch, OpenCV and lanekeep's own; before EGL starts or
    torch is imported (both read the environment once)."""
    os.environ[THREADS_ENV] = str(threads)
    os.environ["LP_NUM_THREADS"] = str(threads)  # Mesa llvmpipe, read when EGL starts
    os.environ["OMP_NUM_THREADS"] = str(threads)  # torch (LaneNet), read at its import
    os.environ.setdefault("MUJOCO_GL", "egl")
    import cv2

    cv2.setNumThreads(threads)


def init_worker(threads: int) -> None:
    """Runs first in every worker: its thread counts, and stop signals left to the parent (an
    idle worker that died of Ctrl-C would break the pool for all)."""
    ignore_stop_signals()
    set_thread_counts(threads)


def spawn_context() -> SpawnContext:
    return multiprocessing.get_context("spawn")


def worker_pool(workers: int, initializer=init_worker, initargs: tuple | None = None
                ) -> ProcessPoolExecutor:
    """`workers` spawned processes, each set up by `initializer` (default: `init_worker` with
    its share of the cores)."""
    args = (worker_threads(workers),) if initargs is None else initargs
    return ProcessPoolExecutor(max_workers=workers, mp_context=spawn_context(),
                               initializer=initializer, initargs=args)
