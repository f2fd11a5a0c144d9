"""Measure the front detectors' centre-line coefficient noise in the closed loop.

    MUJOCO_GL=egl .venv/bin/python tools/measure_detector_noise.py \
        clear_straight clear_curve case2_sharp_turn case3_mild_turn_shade_bumps

Runs each scenario's episode, collects every valid detection's centre line [c0, c1, c2] minus
the true centre line at the pose its frame was taken from, and prints the covariance of the
errors' core (an iterated 97.5% chi-square trim, which keeps ~80%: the tails are heavy) and the
share of detections a tracker gate would reject with it. The
measured_coefficient_covariance of estimators/closed_loop_tracker.toml came from this command
with the four scenarios above.
"""

from __future__ import annotations

import argparse

import numpy as np
from scipy.stats import chi2

from lanekeep.episode import Episode
from lanekeep.ground_truth import lane_truth
from lanekeep.scenario import load_scenario


def coefficient_errors(name: str) -> list[np.ndarray]:
    """Detection minus truth, one row per valid front detection of one episode."""
    scenario = load_scenario(name)
    errors = []
    with Episode(scenario) as episode:
        for _ in range(episode.total_steps):
            step = episode.step()
            truth = lane_truth(episode.world.road, *step.sensed_pose, scenario.road.ego_lane).center
            for detector in episode.front:
                centre = episode.estimator.centre_of(step.estimates[detector])
                if centre is not None:
                    errors.append(np.asarray(centre) - truth)
    return errors


def core_covariance(errors: np.ndarray, quantile: float = 0.975, rounds: int = 5
                    ) -> tuple[np.ndarray, float]:
    """Covariance of the errors' core and the share of rows kept in it."""
    keep = np.ones(len(errors), bool)
    limit = chi2.ppf(quantile, errors.shape[1])
    for _ in range(rounds):
        mean, cov = errors[keep].mean(0), np.cov(errors[keep].T)
        d = errors - mean
        keep = np.einsum("ij,jk,ik->i", d, np.linalg.inv(cov), d) < limit
    return np.cov(errors[keep].T), float(keep.mean())


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("scenarios", nargs="+")
    args = parser.parse_args()
    errors = np.array([e for name in args.scenarios for e in coefficient_errors(name)])
    cov, kept = core_covariance(errors)
    np.set_printoptions(precision=3, suppress=False)
    print(f"{len(errors)} detections, core {kept:.0%}")
    print("covariance:\n", cov)
    print("stds:", np.sqrt(np.diag(cov)))
    gate = chi2.ppf(0.99, 3)
    for scale in (1.0, 2.0, 4.0):
        d2 = np.einsum("ij,jk,ik->i", errors, np.linalg.inv(scale * cov), errors)
        print(f"R = {scale:g} x core: {np.mean(d2 > gate):.1%} of detections beyond the 99% gate")


if __name__ == "__main__":
    main()
