"""Closed-loop episodes: safety in every shipped scenario, accuracy on the clear roads and the
paper's five cases, determinism (dm_env's conformance checks are in tests/envs/test_env.py)."""

import dataclasses

import pytest
from shared_runs import shared
from tiers import CI_SCENARIOS, full_unless

from lanekeep.loop.episode import Episode
from lanekeep.report.seed_summary import fused_vs_track
from lanekeep.scenario.schema import load_scenario, shipped_scenarios
from lanekeep.scoring import statistics as stats

PAPER_CASES = ("case1_building_shadows", "case2_sharp_turn", "case3_mild_turn_shade_bumps",
               "case4_half_shade_straight", "case5_wet_rain_turn")


def _run(name, seconds=None, render_size=None, **changes):
    scenario = load_scenario(name)
    if changes:
        scenario = dataclasses.replace(scenario, **changes)
    with Episode(scenario, render_size=render_size) as episode:
        return episode.run(seconds)


# Episodes that several tests read, run once per session (tests/shared_runs.py): the
# full-length clear roads and paper cases, and 11 s of snow.
LONGER_RUNS = {**{name: None for name in (*PAPER_CASES, "clear_straight", "clear_curve")},
               "snow": 11.0}


def _shared_run(name: str, seconds: float | None):
    return shared(f"default-{name}-{seconds}", lambda: _run(name, seconds))


@pytest.fixture(scope="module")
def paper_reports():
    return {name: _shared_run(name, None) for name in PAPER_CASES}


@pytest.mark.slow
@pytest.mark.parametrize("name", full_unless(shipped_scenarios(), CI_SCENARIOS))
def test_no_lane_departure_with_the_mmae_loop(name):
    """8 s of every shipped scenario with the shipped 1280x720 cameras (the full-length runs are
    `lanekeep bench`). Not at a reduced size: the detectors' pixel parameters and the trackers'
    measured noise belong to the shipped camera, and a half-size camera is another sensor.
    Where a longer run of the scenario is made for another test, this one reads it: its first
    8 s are these 8 s, and the check holds for all of it."""
    if name in LONGER_RUNS:
        report = _shared_run(name, LONGER_RUNS[name])
        assert report.steps >= 80
    else:
        report = _run(name, seconds=8.0)
        assert report.steps == 80
    assert report.lane_departures == 0, report.table()
    assert report.car_max_cm < 120.0, report.table()


@pytest.mark.slow
@pytest.mark.full
def test_snow_keeps_its_lane_through_a_coasting_track():
    """At 8 s in snow model #1 fuses one bad fit whose curvature rate, extrapolated while its
    track then coasts, once steered the car 1.35 m off a 300 m curve by 9.3 s (a departure).
    A coasting track now moves with the ego-motion only."""
    report = _shared_run("snow", 11.0)
    assert report.lane_departures == 0, report.table()
    assert report.car_max_cm < 120.0, report.table()


@pytest.mark.slow
@pytest.mark.parametrize("name", ["clear_straight", "clear_curve"])
def test_fused_rmse_within_10cm_on_clear_roads(name):
    report = _shared_run(name, None)
    assert report.completed and report.lane_departures == 0
    assert report.sources["fused"].rmse_cm <= 10.0, report.table()
    assert report.sources["fused"].valid_share == 1.0


PAPER_FRONT_MODELS = ("hough", "sliding_window")


def _two_model_run(name: str):
    """The paper's own comparison: its two classical front models, the learned rear reference;
    once per session (tests/shared_runs.py)."""
    def run():
        scenario = load_scenario(name)
        est = dataclasses.replace(scenario.estimation, front_detectors=PAPER_FRONT_MODELS)
        with Episode(dataclasses.replace(scenario, estimation=est)) as episode:
            return episode.run()

    return shared(f"two-models-{name}", run)


def _tables(reports) -> str:
    return "\n\n".join(f"{r.scenario} seed {r.seed}\n{r.table()}" for r in reports)


# What "not worse" means (lanekeep/scoring/statistics.py): the fused output non-inferior to a
# track, i.e. the paired 95% interval of fused - track lies below the RMSE's margin; or better
# than it, or equivalent.
NOT_WORSE = ("better", "equivalent", "non-inferior")
# Drawn drives: the file's seed + 1 .. + 8, as `bench --seeds 8`. Sized from a run at five:
# there the fused - lanenet:track interval was [-0.59, +0.13] cm against a 0.11 cm margin
# (inconclusive; sd of the differences 0.29 cm); at eight the same sd gives a half-width of
# 0.24 cm, which resolves the -0.26 cm measured (2026-11-28).
SEEDS_AFTER_NOMINAL = 8


@pytest.fixture(scope="module")
def case3_over_seeds():
    """Case 3 (a turn with shade and bumps: the trackers, the roll, the MMAE all at work) on
    eight drawn drives, 10 s each at the shipped camera size."""
    nominal = load_scenario("case3_mild_turn_shade_bumps").seed
    return [_run("case3_mild_turn_shade_bumps", seconds=10.0, seed=nominal + k)
            for k in range(1, SEEDS_AFTER_NOMINAL + 1)]


# A strict xfail from #59's tone curve (LaneNet trained on the lifted shade lost case 3's
# crushed shade; seed 6 left the road) until LaneNet was fine-tuned on that world
# (2026-11-29, detectors/weights/MODEL_CARD.md): it passes again, so the mark went.
@pytest.mark.slow
@pytest.mark.full
def test_fused_is_non_inferior_to_every_models_own_track_over_seeds(case3_over_seeds):
    """The default loop's fused output against each front model's own Kalman track, paired
    over eight seeds within one case, on the steps where both had an estimate: non-inferior
    within the RMSE's margin (max(0.1 cm, 5%)), not merely "no difference found". Before
    (to 2026-11-28) this paired five cases at one seed each and passed on anything short of
    "worse", which a 10 cm regression in one case did (docs/statistics.md#margins)."""
    for track in ("hough:track", "sliding_window:track", "lanenet:track"):
        p = fused_vs_track(case3_over_seeds, track)
        assert p["n"] == SEEDS_AFTER_NOMINAL and p["verdict"] in NOT_WORSE, \
            f"{track}: {p}\n{_tables(case3_over_seeds)}"
    assert all(r.lane_departures == 0 for r in case3_over_seeds), _tables(case3_over_seeds)


@pytest.mark.slow
@pytest.mark.full
def test_no_departure_in_the_paper_cases(paper_reports):
    assert all(r.lane_departures == 0 for r in paper_reports.values()), \
        _tables(paper_reports.values())


# The two-model loop's guard runs the three paper cases where that loop is weakest (one drive
# each with the shipped binarisation, docs/experiments.md, 2026-11-29, "Classical models that
# find paint in the bird's-eye view", the "before" column: case 3 fused 8.1 cm, case 5 car max
# 37.3 cm, case 2 car max 20.1 cm), not cases 1 and 4 (fused 0.9 and 1.1 cm, car max 3.2 and
# 2.5 cm), for CI's time; those two run in the default loop here and in paper mode. CI drives
# case 2 (tests/tiers.py); cases 3 and 5 are the `full` tier.
TWO_MODEL_CASES = full_unless(("case2_sharp_turn", "case3_mild_turn_shade_bumps",
                               "case5_wet_rain_turn"), CI_SCENARIOS)


@pytest.mark.slow
@pytest.mark.parametrize("name", TWO_MODEL_CASES)
def test_the_papers_two_models_keep_the_lane(name):
    """The MMAE output of the paper's two classical front models (its Tables 3-4) drives every
    case without a departure. One case a test, so that test workers share the five runs."""
    report = _two_model_run(name)
    assert report.completed and report.lane_departures == 0, report.table()


@pytest.mark.slow
@pytest.mark.parametrize("name", TWO_MODEL_CASES)
def test_the_papers_two_models_fused_is_within_the_margin_of_their_worse_track(name):
    """Paper Tables 3-4's loop, one case a test at its nominal seed: the fused output is not
    worse than the worse of the two models' own tracks by more than the RMSE's margin
    (statistics.MARGINS). One seed is one drive, so this is a guard on each case, not a
    verdict (a verdict pairs seeds within a case: `lanekeep bench CASE --mode paper --seeds
    10`). Before (to 2026-11-28) this paired the five cases as if they were seeds, where one
    case 10 cm worse went unnoticed."""
    report = _two_model_run(name)
    tracks = [report.sources[t].rmse_cm for t in ("hough:track", "sliding_window:track")]
    worse_track = max(tracks)
    allowed = worse_track + stats.margin_for("rmse_cm").of(worse_track)
    assert report.sources["fused"].rmse_cm <= allowed, report.table()


def test_same_scenario_twice_gives_identical_metrics():
    a = _run("clear_curve", seconds=3.0, render_size=(640, 360)).to_dict()
    b = _run("clear_curve", seconds=3.0, render_size=(640, 360)).to_dict()
    a.pop("wall_s"), b.pop("wall_s")
    assert a == b


def test_unknown_detector_is_a_clear_error():
    scenario = load_scenario("clear_straight")
    bad = dataclasses.replace(scenario, estimation=dataclasses.replace(
        scenario.estimation, front_detectors=("hough", "no_such_detector")))
    with pytest.raises(ValueError, match="no_such_detector"):
        Episode(bad, render_size=(320, 180))
