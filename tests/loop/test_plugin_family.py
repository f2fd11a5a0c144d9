"""A plug-in that subclasses a built-in detector and changes only its `name` runs the built-in's
loop (detectors/registry.py `builtin_family`): the same tracker noise and MMAE prior, the same
paper-mode window, LaneNet's batch with the LaneNet reference, so the same episode to the bit.
Before, a sham of LaneNet got the pooled tracker noise of an unknown plug-in and another loop."""

import numpy as np
from helpers import small_scenario

from lanekeep.loop.episode import Episode

SIZE = (320, 180)


def _scenario(front: tuple[str, ...], mode: str = "default", seconds: float = 4.0):
    return small_scenario("clear_curve", seconds, seed=0,
                          estimation={"mode": mode, "front_detectors": front})


def _run(front: tuple[str, ...]):
    with Episode(_scenario(front), render_size=SIZE) as episode:
        steps = [episode.step() for _ in range(episode.total_steps)]
        return episode, steps, episode.report()


def test_a_sham_of_lanenet_runs_the_lanenet_loop_to_the_bit():
    built_in, steps_a, a = _run(("hough", "sliding_window", "lanenet"))
    sham, steps_b, b = _run(("hough", "sliding_window", "plugins.sham:Sham"))
    assert list(sham.driver.front) == ["hough", "sliding_window", "sham"]
    assert np.array_equal(sham.driver.estimator.tracker_configs["sham"].coefficient_r,
                          built_in.driver.estimator.tracker_configs["lanenet"].coefficient_r)
    assert np.array_equal(sham.driver.estimator.mmae._prior, built_in.driver.estimator.mmae._prior)
    assert b.sources["fused"].rmse_cm == a.sources["fused"].rmse_cm
    assert b.sources["sham:track"].rmse_cm == a.sources["lanenet:track"].rmse_cm
    assert [s.truth_offset_m for s in steps_b] == [s.truth_offset_m for s in steps_a]
    assert (b.car_rms_cm, b.car_max_cm) == (a.car_rms_cm, a.car_max_cm)


def test_a_sham_of_hough_gets_hough_s_paper_window():
    front = ("plugins.sham:ShamHough", "sliding_window")
    with Episode(_scenario(("hough", "sliding_window"), "paper"), render_size=SIZE) as built_in, \
            Episode(_scenario(front, "paper"), render_size=SIZE) as sham:
        assert sham.driver.front["sham_hough"].window == built_in.driver.front["hough"].window
        assert sham.driver.front["sham_hough"].window.x_far_m == 30.0  # paper_mode.PAPER_WINDOWS
