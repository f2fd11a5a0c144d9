"""LaneNet in the closed loop: a third front model beside the classical two and the rear
reference, through the N-model MMAE, with its GRU state carried from step to step."""


import numpy as np
import pytest
from helpers import small_scenario

from lanekeep.loop.episode import Episode


@pytest.mark.slow
def test_three_front_models_and_the_learned_reference_keep_the_lane():
    scenario = small_scenario("clear_curve", 6.0, estimation={
        "front_detectors": ("hough", "sliding_window", "lanenet"),
        "reference_detector": "lanenet"})
    with Episode(scenario, render_size=(640, 360)) as episode:
        steps = [episode.step() for _ in range(episode.total_steps)]
        report = episode.report()
    assert all(len(s.probabilities) == 3 for s in steps)
    assert all(abs(sum(s.probabilities) - 1.0) < 1e-9 for s in steps)
    # Each step hands on the MMAE's residuals (tools/trace_estimation.py reads them): once the
    # car has driven past the road its front models saw, every model is compared.
    assert all(s.mmae_residuals_m.shape == (3,) for s in steps)
    compared = [s for s in steps if np.isfinite(s.mmae_residuals_m).all()]
    assert len(compared) > len(steps) // 2
    assert max(np.abs(s.mmae_residuals_m).max() for s in compared) < 0.5
    assert report.lane_departures == 0
    assert report.sources["lanenet"].valid_share > 0.9
    assert report.sources["reference"].valid_share > 0.9
    assert report.sources["reference"].rmse_cm < 10.0
    # The learned model carried its state: it holds the GRU memory after the last step.
    lanenet = episode.driver.front["lanenet"]
    assert lanenet._state is not None and np.isfinite(lanenet.model.alpha.item())
