"""Detections on two threads give what one thread gives: the same estimates, events, error
counts and report, in the same order (lanekeep/driver/detection.py)."""

from __future__ import annotations

import threading
from collections import Counter

import numpy as np
import pytest
from helpers import small_scenario

from lanekeep.core.workers import THREADS_ENV
from lanekeep.detectors.base import LaneEstimate
from lanekeep.driver.detection import DetectionRunner, DetectJob, group_jobs, run_job
from lanekeep.loop.episode import Episode


class _Fake:
    """A detector that reports which thread ran it; `meet` (a barrier) makes it wait there
    (releasing the GIL, as OpenCV and torch do) until another detection is under way at the
    same time; `fail` makes it raise."""

    def __init__(self, offset: float, meet: threading.Barrier | None = None,
                 fail: bool = False) -> None:
        self.offset, self.meet, self.fail = offset, meet, fail
        self.threads: list[str] = []

    def reset(self) -> None:
        pass

    def detect(self, frame: np.ndarray) -> LaneEstimate:
        self.threads.append(threading.current_thread().name)
        if self.meet is not None:
            self.meet.wait()
        if self.fail:
            raise RuntimeError("boom")
        return LaneEstimate(valid=True, offset_m=self.offset, x_m=4.0)


def _jobs(detectors) -> list[DetectJob]:
    frame = np.zeros((4, 4, 3), np.uint8)
    return group_jobs([(f"d{i}", d, frame) for i, d in enumerate(detectors)])


def test_two_threads_share_the_jobs_and_keep_their_order():
    # Each detection waits at the barrier for a second one running at the same time: four
    # jobs pass it in two rounds of two, one job of each thread a round; on one thread the
    # first job would wait in vain (the timeout only ends a hang: the barrier breaks and the
    # detections fail).
    meet = threading.Barrier(2, timeout=60.0)
    detectors = [_Fake(0.1 * i, meet=meet, fail=(i == 2)) for i in range(4)]
    runner = DetectionRunner(lambda: 2)
    try:
        results = runner.run(_jobs(detectors), runner.parallel_now())
    finally:
        runner.close()
    assert not meet.broken
    assert [r[0].estimate.offset_m for r in results if r[0].estimate.valid] == \
        pytest.approx([0.0, 0.1, 0.3])
    assert [bool(r[0].event) for r in results] == [False, False, True, False]
    assert results[2][0].event == "failed: boom" and not results[2][0].estimate.valid
    ran_on = Counter(t for d in detectors for t in d.threads)
    assert sorted(ran_on.values()) == [2, 2], ran_on  # four jobs in two rounds, not four


def test_one_thread_runs_every_job_itself():
    detectors = [_Fake(0.1 * i) for i in range(3)]
    runner = DetectionRunner(lambda: 1)
    results = runner.run(_jobs(detectors), runner.parallel_now())
    runner.close()
    assert not runner.parallel_now()
    assert [r[0].estimate.offset_m for r in results] == pytest.approx([0.0, 0.1, 0.2])
    assert {t for d in detectors for t in d.threads} == {threading.current_thread().name}


class _Model:
    def parameters(self):  # what marks a torch module for `group_jobs`
        return iter(())


class _Learned(_Fake):
    """Two of these share one model: they must run as one job, never on two threads."""

    def __init__(self, offset: float, model: _Model) -> None:
        super().__init__(offset)
        self.model = model

    @staticmethod
    def detect_many(detectors, frames):
        return [LaneEstimate(valid=True, offset_m=d.offset + 1.0, x_m=4.0) for d in detectors]


def test_detectors_sharing_a_model_are_one_batched_job():
    model = _Model()
    frame = np.zeros((4, 4, 3), np.uint8)
    named = [("a", _Fake(0.0), frame), ("b", _Learned(0.1, model), frame),
             ("c", _Learned(0.2, model), frame)]
    jobs = group_jobs(named)
    assert [job.names for job in jobs] == [("b", "c"), ("a",)]
    results = run_job(jobs[0])
    assert [r.estimate.offset_m for r in results] == pytest.approx([1.1, 1.2])  # the batch
    # on two threads each learned detector is a job of its own, still first
    assert [job.names for job in group_jobs(named, parallel=True)] == [("b",), ("c",), ("a",)]


def _run(name: str, threads: int, monkeypatch) -> tuple[dict, list]:
    monkeypatch.setenv(THREADS_ENV, str(threads))
    scenario = small_scenario(name, 1.5)
    with Episode(scenario, render_size=(640, 360)) as episode:
        assert episode.driver.detection.parallel_now() == (threads >= 2)
        steps = [episode.step() for _ in range(episode.total_steps)]
        report = episode.report().to_dict()
    estimates = [{name: (e.valid, e.offset_m, e.x_m, e.confidence, e.reason,
                         None if e.left is None else tuple(e.left),
                         None if e.right is None else tuple(e.right))
                  for name, e in step.estimates.items()} for step in steps]
    return report, [(estimates[k], steps[k].events, steps[k].steer) for k in range(len(steps))]


# night: LaneNet's front and rear on two threads at once, each thread's torch count its own (a
# count shared between the threads once let one of them run on two: other numbers)
@pytest.mark.parametrize("name", ["case3_mild_turn_shade_bumps", "night"])
def test_an_episode_on_two_threads_equals_one_on_one(name, monkeypatch):
    report_1, steps_1 = _run(name, 1, monkeypatch)
    report_2, steps_2 = _run(name, 2, monkeypatch)
    for key in ("wall_s",):  # the only figure that may differ
        report_1.pop(key, None)
        report_2.pop(key, None)
    assert steps_1 == steps_2
    assert report_1 == report_2
