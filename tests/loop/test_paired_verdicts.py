"""Paired verdicts on closed loops: a deliberately degraded front model is found `worse`
(lanekeep/scoring/statistics.py over seeds), so a verdict can catch a real regression. Full
1280x720 cameras (the detectors' pixel parameters belong to them), a few seconds per seed."""

import dataclasses
import sys
from pathlib import Path

import pytest

from lanekeep.loop.episode import Episode
from lanekeep.scenario.schema import load_scenario
from lanekeep.scoring import statistics as stats

ROOT = Path(__file__).resolve().parents[2]
SEEDS = (0, 1, 2)  # the file's nominal drive and two drawn starts
SECONDS = 4.0


def _fused_rmse(front: str, seed: int) -> float:
    scenario = load_scenario("clear_straight")
    scenario = dataclasses.replace(scenario, seed=seed, estimation=dataclasses.replace(
        scenario.estimation, front_detectors=(front,)))
    with Episode(scenario) as episode:
        report = episode.run(SECONDS)
    assert report.completed and report.lane_departures == 0, report.table()
    return report.sources["fused"].rmse_cm


@pytest.mark.slow
@pytest.mark.full
def test_a_5cm_bias_on_the_front_model_is_found_worse(monkeypatch):
    """examples/sabotage.py's hough, every lane it sees 5 cm to the left, against hough itself,
    paired over three seeds: `worse` beyond the RMSE's margin, by about the bias (its trackers
    also get the pooled noise a plug-in gets, which alone moves the RMSE by far less)."""
    monkeypatch.syspath_prepend(str(ROOT))
    biased = [_fused_rmse("examples.sabotage:BiasedHough", s) for s in SEEDS]
    honest = [_fused_rmse("hough", s) for s in SEEDS]
    # the RMSE's declared margin (max(0.1 cm, 5%)) on the log scale, given back in cm
    p = stats.paired(biased, honest, metric="rmse_cm")
    assert p.verdict == "worse", (p, biased, honest)
    assert 2.5 < p.diff < 6.0, (p, biased, honest)
    assert p.ci95[0] > p.margin > 0.0 and p.p_worse < stats.ALPHA_ONE_SIDED
    # the same runs against themselves: a zero difference inside the margin
    assert stats.paired(honest, honest, metric="rmse_cm").verdict == "equivalent"
    sys.modules.pop("examples.sabotage", None)
