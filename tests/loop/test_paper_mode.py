"""The paper's own loop (`[estimation] mode = "paper"`, lanekeep/loop/paper_mode.py): its settings,
and on fixed seeds, with some of our deviations kept (named below), the pattern of paper 001:
no departure in any of its five cases; in the
sharp turn (case 2) model #2, with its small region of interest, is clearly worse than model
#1; in the building shadows (case 1) model #1
loses the lane and the MMAE follows model #2 there (paper Fig. 12)."""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np
import pytest
from shared_runs import shared

from lanekeep.control.pid import PaperGains
from lanekeep.detectors.config import load_config
from lanekeep.driver.paper_mode import PAPER_WINDOWS, front_detector_config
from lanekeep.loop.episode import Episode
from lanekeep.loop.paper_mode import with_mode
from lanekeep.scenario.schema import load_scenario
from lanekeep.scoring import statistics as stats

PAPER_CASES = ("case1_building_shadows", "case2_sharp_turn", "case3_mild_turn_shade_bumps",
               "case4_half_shade_straight", "case5_wet_rain_turn")
HOUGH, SLIDING = 0, 1  # model #1, model #2
# Paper mode is the paper's loop to the letter (every deviation off). That loop leaves the lane
# in cases 1, 4 and 5 at their nominal seeds; kept alone, our controller, our PID input or our
# binarisation each keeps it there (2026-11-29, docs/paper_mode.md#to-the-letter). Two
# configurations are tested, each named by the deviations it keeps:
# - LETTER_OUR_CONTROLLER, the letter with our controller, the one deviation that is the car's
#   and not the estimator's: case 1 at its nominal seed keeps the lane (a guard on that drive,
#   not a rate), and the case 1 pattern (not reproduced by these criteria, strict xfail);
# - SIZED, the paper's loop with our tuned binarisation, eq. 8 with each tracker's variance and
#   a floor of 1e-3 (paper mode until 2026-11-29): the case 2 seeds and pattern, sized for it,
#   their assertions unchanged. With our controller alone case 2 departs on three of these
#   five seeds (3, 5, 6). The letter's own figures, over seeds, are in the docs.
LETTER_OUR_CONTROLLER = ("controller",)
SIZED = ("binarisation", "residual_covariance", "probability_floor")


@dataclass
class PaperTrace:
    """Per step, from the scoring side: where the car was and what the models did."""

    curvature_ahead: list[float] = field(default_factory=list)  # road curvature 4 m ahead
    shaded_ahead: list[bool] = field(default_factory=list)  # the 4 m point in a cast shadow
    selected: list[int] = field(default_factory=list)
    errors_m: list[list[float]] = field(default_factory=list)  # per model, NaN when invalid

    def arrays(self):
        return (np.asarray(self.curvature_ahead), np.asarray(self.shaded_ahead),
                np.asarray(self.selected), np.asarray(self.errors_m, dtype=float))


def paper_run(name: str, seed: int | None = None, keeps: tuple[str, ...] = SIZED):
    """The paper's loop on a paper case with its trace (at `seed`, None: the file's own, its
    nominal drive), once per session."""
    return shared(f"paper-{name}-{seed}-{'+'.join(keeps)}", lambda: _paper_run(name, seed, keeps))


def _paper_run(name: str, seed: int | None, keeps: tuple[str, ...]):
    scenario = with_mode(load_scenario(name), "paper")
    scenario = replace(scenario, estimation=replace(scenario.estimation, paper_keeps=keeps))
    if seed is not None:
        scenario = replace(scenario, seed=seed)
    trace = PaperTrace()
    with Episode(scenario) as episode:
        road, conditions = episode.world.road, episode.world.conditions
        models = list(episode.driver.front)

        def on_step(step, total):
            x, y, yaw = step.sensed_pose
            s, _ = road.local_coordinates(np.array([x, y]))
            ahead = np.array([x + 4.0 * np.cos(yaw), y + 4.0 * np.sin(yaw)])
            trace.curvature_ahead.append(float(road.curvature_at(float(s) + 4.0)))
            trace.shaded_ahead.append(bool(conditions.shaded(ahead)))
            trace.selected.append(step.selected)
            row = []
            for name in models:
                e = step.estimates[name]
                truth = step.truth.offset_at(e.x_m)  # computed once, by the episode's scoring
                row.append(e.offset_m - truth if e.valid else np.nan)
            trace.errors_m.append(row)

        report = episode.run(on_step=on_step)
    return report, trace


def test_paper_mode_gives_each_model_its_own_window_and_the_pid_table_2():
    base = load_config()
    for name, (near, far, half) in PAPER_WINDOWS.items():
        front = front_detector_config(name, "paper").profiles.front
        assert (front.x_near_m, front.x_far_m, front.y_half_m) == (near, far, half)
        assert front_detector_config(name, "default") is None  # the shipped config
    long_range, short_range = PAPER_WINDOWS["hough"], PAPER_WINDOWS["sliding_window"]
    assert long_range[1] > base.profiles.front.x_far_m > short_range[1]
    straight, curvy = PaperGains().gains(False), PaperGains().gains(True)
    assert curvy.kp == pytest.approx(2 * straight.kp) and straight.ki == 0.0


def test_each_mode_has_its_own_front_models_and_the_learned_reference():
    """Our loop runs LaneNet beside the paper's two classical models; the paper's loop runs its
    two. Both take the learned detector on the rear camera as the reference (the paper's is
    a learned one). Switching the mode switches default models and keeps named ones."""
    ours = load_scenario("clear_curve")
    assert ours.estimation.front_detectors == ("hough", "sliding_window", "lanenet")
    assert ours.estimation.reference_detector == "lanenet"
    paper = with_mode(ours, "paper")
    assert paper.estimation.front_detectors == ("hough", "sliding_window")
    assert paper.estimation.reference_detector == "lanenet"
    assert with_mode(paper, "default").estimation == ours.estimation
    named = replace(ours, estimation=replace(ours.estimation, front_detectors=("hough",)))
    assert with_mode(named, "paper").estimation.front_detectors == ("hough",)


# The letter's closed-loop guard is case 1's nominal drive, the run the case 1 xfail reads too.
# The other cases at their nominal seeds kept the lane as well (2026-11-29), but over seeds the
# letter with our controller departs 5 of 10 times in case 2 and in case 4 and 7 times in case 5
# (docs/paper_mode.md): a nominal drive there guards little, for CI's time.


@pytest.mark.slow
def test_the_letter_with_our_controller_keeps_the_lane_in_case1():
    report, _ = paper_run("case1_building_shadows", keeps=LETTER_OUR_CONTROLLER)
    assert report.completed and report.lane_departures == 0, report.table()


CASE2_SEEDS = (2, 3, 4, 5, 6)  # the file's own seed (2), then four drawn drives


@pytest.mark.slow
@pytest.mark.full
@pytest.mark.parametrize("seed", CASE2_SEEDS)
def test_the_sized_paper_loop_keeps_the_lane_in_case2_on_every_seed(seed):
    """The seeds the next test pairs: each drives the sharp turn without a departure (one
    seed a test, so that test workers share the runs)."""
    report, _ = paper_run("case2_sharp_turn", None if seed == 2 else seed)
    assert report.completed and report.lane_departures == 0, report.table()


@pytest.mark.slow
@pytest.mark.full
def test_case2_model_2_is_worse_in_the_sharp_turn():
    """Paper Table 3: model #2's RMSE 47.29 cm, model #1's 21.12 cm (2.24x). Ours, paired over
    five seeds (lanekeep/scoring/statistics.py): model #2 `worse` over the episode and in the
    turn alone. Measured 2026-11-27 (`lanekeep bench case2_sharp_turn --mode paper --seeds 5`):
    +2.16 cm [+1.21, +3.12] over the episode, ratios 1.12-1.35 by seed. (The paper's MMAE
    then follows model #1 through the turn; ours does not, for its reference is model #2's
    own algorithm on the rear camera and shares its bias in the turn: see
    docs/paper_mode.md.) Before this was a ratio on one seed, relaxed from 1.2 to 1.1."""
    hough, sliding, turn_hough, turn_sliding = [], [], [], []
    for seed in CASE2_SEEDS:
        report, trace = paper_run("case2_sharp_turn", None if seed == 2 else seed)
        curvature, _, _, errors = trace.arrays()
        turn = np.abs(curvature) > 0.01  # the 40 m arc and the steep ends of its clothoids
        in_turn = np.sqrt(np.nanmean(errors[turn] ** 2, axis=0))
        hough.append(report.sources["hough"].rmse_cm)
        sliding.append(report.sources["sliding_window"].rmse_cm)
        turn_hough.append(100.0 * in_turn[HOUGH])
        turn_sliding.append(100.0 * in_turn[SLIDING])
    overall = stats.paired(sliding, hough, metric="rmse_cm")  # worse beyond the margin
    assert overall.verdict == "worse", (overall, hough, sliding)
    in_the_turn = stats.paired(turn_sliding, turn_hough, metric="rmse_cm")
    assert in_the_turn.verdict == "worse", (in_the_turn, turn_hough, turn_sliding)


@pytest.mark.slow
@pytest.mark.xfail(strict=True, reason=(
    "Not reproduced since [realism] (#44, 2026-11-27): with paint 40-70 DN above the road, "
    "model #1 (hough) was re-tuned to binarise against the road beside each ridge, and it now "
    "finds the lane in case 1's shade (valid in 100% of the shaded steps; this test needs "
    "< 50%); a frame-wide threshold as the paper's (1.2x the ROI's 75th percentile, with or "
    "without a floor of 90) still gave 96%, since the camera's auto-exposure lifts a shaded "
    "road. Reproducing the paper's case 1 pattern is [observer] #43's part 3. Strict: this "
    "fails the suite the day the pattern comes back, so that this mark goes. 2026-11-29, paper "
    "mode to the letter (fixed thresholds) with our controller kept, the nominal drive: model "
    "#1 valid in 68% of the shaded steps (99% in sun), model #2 in 92%, the MMAE on model #2 in "
    "65%: model #1 is worse in the shade (docs/paper_mode.md) but does not lose the lane by "
    "these criteria; to the letter the drive departs."))
def test_case1_model_1_loses_the_lane_in_shadow_and_the_mmae_follows_model_2():
    report, trace = paper_run("case1_building_shadows", keeps=LETTER_OUR_CONTROLLER)
    _, shaded, selected, errors = trace.arrays()
    assert shaded.sum() >= 20  # the building shadows lie across the car's path
    hough_valid = np.isfinite(errors[:, HOUGH])
    assert hough_valid[shaded].mean() < 0.5 < 0.9 < hough_valid[~shaded].mean()
    assert np.isfinite(errors[shaded, SLIDING]).all()
    assert np.mean(selected[shaded] == SLIDING) > 0.9
