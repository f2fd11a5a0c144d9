"""One control step's detections, on two threads when the process may use two cores.

Why: the detectors of a step are independent (each reads one frame and keeps its own state),
and OpenCV and torch release the GIL, so on a 2-core machine the classical front detectors run
beside the learned ones: the step waits for the longer half instead of the sum. Both threads
take jobs from one list (longest first), so the split balances itself; every result goes back
to its job's place, so the estimates, events and error counts come out in the same order and
with the same values on one thread or two (tests/loop/test_parallel_detection.py).

On one thread, learned detectors of one class and weights (front LaneNet, or a plug-in
subclass that keeps its `detect`, and the LaneNet reference) run as one batch
(`LaneNetDetector.detect_many`, 1.1x less CPU than two calls); on two threads they run apart,
one per thread, each on one torch thread (detectors/lanenet.py).
A bench worker has one core (lanekeep/core/workers.py) and runs every job on its own thread.
"""

from __future__ import annotations

import threading
import time
from collections.abc import Callable, Sequence
from concurrent.futures import Future, ThreadPoolExecutor
from dataclasses import dataclass

import numpy as np

from lanekeep.core.busy import all_cores_busy
from lanekeep.detectors.base import Detector, LaneEstimate


@dataclass(frozen=True)
class DetectJob:
    """Detectors that run together: `names[i]` reads `frames[i]` with `detectors[i]`."""

    names: tuple[str, ...]
    detectors: tuple[Detector, ...]
    frames: tuple[np.ndarray, ...]


@dataclass(frozen=True)
class Detected:
    """What one detector gave: its estimate (invalid after a fault), the event that says why
    it failed ("" when it did not), and the wall time of its job."""

    estimate: LaneEstimate
    event: str
    seconds: float


def safe_detect(detector: Detector, frame: np.ndarray) -> tuple[LaneEstimate, str]:
    """A detector that raises or returns garbage counts as a miss, with an event."""
    try:
        estimate = detector.detect(frame)
    except Exception as err:  # noqa: BLE001 - any detector fault is a miss, not a crash
        return LaneEstimate.invalid(f"error: {err}"), f"failed: {err}"
    if not isinstance(estimate, LaneEstimate):
        return LaneEstimate.invalid("not a LaneEstimate"), f"returned {type(estimate).__name__}"
    return estimate, ""


def _is_learned(detector: Detector) -> bool:
    model = getattr(detector, "model", None)
    return model is not None and hasattr(model, "parameters")  # a torch module


def _batch_class(detector: Detector) -> type:
    """The class whose `detect_many` may run `detector` in a batch: the nearest in its MRO
    that defines one, so that a plug-in subclass of LaneNet that keeps LaneNet's `detect`
    batches with the LaneNet reference as LaneNet does; its own class if it overrides
    `detect` (a batch would skip the override) or no class defines one."""
    cls = type(detector)
    owner = next((c for c in cls.__mro__ if "detect_many" in vars(c)), None)
    return owner if owner is not None and cls.detect is owner.detect else cls


def _batch_key(detector: Detector) -> tuple:
    return _batch_class(detector), getattr(detector, "weights_path", None)


def _run_batch(detectors: list[Detector], frames: list[np.ndarray]
               ) -> list[tuple[LaneEstimate, str]]:
    """Detectors of one batch class and weights (`_batch_key`): one `detect_many` call where
    that class defines it and `detect` is its own (LaneNet), else one at a time; a batch that
    fails is run one at a time to find whose fault it was."""
    owner = _batch_class(detectors[0])
    many = getattr(owner, "detect_many", None) if "detect_many" in vars(owner) else None
    if many is not None and len(detectors) > 1:
        try:
            estimates = many(detectors, frames)
            if all(isinstance(e, LaneEstimate) for e in estimates):
                return [(e, "") for e in estimates]
        except Exception:  # noqa: BLE001 - retried one at a time below
            pass
    return [safe_detect(d, f) for d, f in zip(detectors, frames, strict=True)]


def run_job(job: DetectJob) -> list[Detected]:
    """A job's detections, batched where its detectors can be, in the job's order."""
    start = time.perf_counter()
    batches: dict[tuple, list[int]] = {}
    for i, detector in enumerate(job.detectors):
        batches.setdefault(_batch_key(detector), []).append(i)
    results: list[tuple[LaneEstimate, str]] = [None] * len(job.names)  # type: ignore[list-item]
    for indices in batches.values():
        done = _run_batch([job.detectors[i] for i in indices], [job.frames[i] for i in indices])
        for i, result in zip(indices, done, strict=True):
            results[i] = result
    seconds = (time.perf_counter() - start) / len(job.names)
    return [Detected(estimate, event, seconds) for estimate, event in results]


def group_jobs(named: Sequence[tuple[str, Detector, np.ndarray]], parallel: bool = False
               ) -> list[DetectJob]:
    """The step's jobs, learned detectors (a torch module as `model`) first: they are the
    longest. On one thread the learned ones are one job, so that those of one class and
    weights run as one batch (`run_job`: LaneNet's front and rear, one network call); on two
    threads each is its own job, so that the two threads share them out. Both give the same
    numbers (a batch item's outputs do not depend on the others)."""
    learned = [(n, d, f) for n, d, f in named if _is_learned(d)]
    jobs = [DetectJob((name,), (detector,), (frame,))
            for name, detector, frame in named if not _is_learned(detector)]
    if parallel:
        return [DetectJob((n,), (d,), (f,)) for n, d, f in learned] + jobs
    if learned:
        jobs.insert(0, DetectJob(tuple(n for n, _, _ in learned),
                                 tuple(d for _, d, _ in learned),
                                 tuple(f for _, _, f in learned)))
    return jobs


class DetectionRunner:
    """Runs a step's jobs on this thread and, while `threads()` says two or more, on one helper
    thread too (a bench worker's share changes when the other episodes end: workers.py)."""

    def __init__(self, threads: Callable[[], int]) -> None:
        self._threads = threads
        self._pool: ThreadPoolExecutor | None = None

    def parallel_now(self) -> bool:
        """Whether this step's jobs run on two threads (ask once per step)."""
        return self._threads() >= 2

    def run(self, jobs: Sequence[DetectJob], parallel: bool) -> list[list[Detected]]:
        """Each job's results, in the jobs' order."""
        results: list[list[Detected] | None] = [None] * len(jobs)
        if not parallel or len(jobs) < 2:
            return [run_job(job) for job in jobs]
        if self._pool is None:
            self._pool = ThreadPoolExecutor(1, thread_name_prefix="lanekeep-detect")
        lock = threading.Lock()
        queue = list(range(len(jobs)))

        def drain() -> None:
            while True:
                with lock:
                    if not queue:
                        return
                    index = queue.pop(0)
                results[index] = run_job(jobs[index])

        with all_cores_busy():  # the recorder's writer waits (lanekeep/core/busy.py)
            helper: Future = self._pool.submit(drain)
            drain()
            helper.result()
        return [r for r in results if r is not None]

    def close(self) -> None:
        if self._pool is not None:
            self._pool.shutdown(wait=True)
            self._pool = None
