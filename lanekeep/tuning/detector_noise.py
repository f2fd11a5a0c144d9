"""The front detectors' centre-line coefficient noise in the closed loop: the measurement
covariances (R) of estimators/closed_loop_tracker.toml.

Every valid detection's centre line [c0, c1, c2] minus the true centre line at the pose its
frame was taken from, per front detector; the covariance of the errors' core (an iterated 97.5%
chi-square trim, which keeps ~80%: the tails are heavy). The truth is the least-squares
quadratic of the exact road centre over the front detectors' own fit window (detectors/
detectors.toml [profiles.front]), so that the errors are the detectors' and not the difference
between two windows' quadratic fits of a curving road.
"""

from __future__ import annotations

from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from scipy.stats import chi2

from lanekeep.core.workers import set_thread_counts, worker_pool
from lanekeep.scenario.schema import load_scenario


def front_window() -> tuple[float, float]:
    """(near, far) of the front detectors' ground window, where they fit their lines."""
    from lanekeep.detectors.config import load_config

    front = load_config().profiles.front
    return tuple(sorted((float(front.x_near_m), float(front.x_far_m))))


def coefficient_errors(name: str | Path, fit_range_m: tuple[float, float]
                       ) -> dict[str, list[np.ndarray]]:
    """Per front detector, detection minus truth, one row per valid detection of one
    episode."""
    from lanekeep.loop.episode import Episode
    from lanekeep.scoring.truth import lane_truth

    scenario = load_scenario(name)
    errors: dict[str, list[np.ndarray]] = {}
    with Episode(scenario) as episode:
        for _ in range(episode.total_steps):
            step = episode.step()
            truth = lane_truth(episode.world.road, *step.sensed_pose, scenario.road.ego_lane,
                               fit_range_m=fit_range_m).center
            for detector in episode.driver.front:
                centre = episode.driver.estimator.centre_of(step.estimates[detector])
                if centre is not None:
                    errors.setdefault(detector, []).append(np.asarray(centre) - truth)
    return errors


def errors_per_scenario(scenarios: Sequence[str], fit_range_m: tuple[float, float],
                        workers: int) -> Iterator[dict[str, list[np.ndarray]]]:
    """`coefficient_errors` of each scenario, in order, `workers` episodes at a time (Ctrl-C
    reaches the workers: a measurement keeps nothing half done)."""
    with worker_pool(workers, initializer=set_thread_counts) as pool:
        yield from pool.map(coefficient_errors, scenarios, [fit_range_m] * len(scenarios))


def core_covariance(errors: np.ndarray, quantile: float = 0.975, rounds: int = 5
                    ) -> tuple[np.ndarray, np.ndarray, float]:
    """Mean and covariance of the errors' core, and the share of rows kept in it."""
    keep = np.ones(len(errors), bool)
    limit = chi2.ppf(quantile, errors.shape[1])
    for _ in range(rounds):
        mean, cov = errors[keep].mean(0), np.cov(errors[keep].T)
        d = errors - mean
        keep = np.einsum("ij,jk,ik->i", d, np.linalg.inv(cov), d) < limit
    return errors[keep].mean(0), np.cov(errors[keep].T), float(keep.mean())


@dataclass(frozen=True)
class Fit:
    """The robust core of one set of coefficient errors."""

    count: int
    mean: np.ndarray
    cov: np.ndarray
    kept: float

    @classmethod
    def of(cls, errors: np.ndarray) -> Fit:
        mean, cov, kept = core_covariance(errors)
        return cls(len(errors), mean, cov, kept)

    def report(self, title: str, errors: np.ndarray) -> list[str]:
        """Its summary, and the share of `errors` a 99% gate would reject with R = 1, 2 and 4
        times the core's covariance."""
        lines = [f"{title}: {self.count} detections, core {self.kept:.0%}",
                 f"  core mean (bias): {self.mean}",
                 f"  stds: {stds_text(self.cov)}"]
        gate = chi2.ppf(0.99, 3)
        for scale in (1.0, 2.0, 4.0):
            d2 = np.einsum("ij,jk,ik->i", errors, np.linalg.inv(scale * self.cov), errors)
            lines.append(f"  R = {scale:g} x core: {np.mean(d2 > gate):.1%} of detections "
                         "beyond the 99% gate")
        return lines


def number(value: float) -> str:
    """3 significant digits, TOML's float syntax with a short exponent: 3.18e-3."""
    mantissa, exponent = f"{value:.2e}".split("e")
    return f"{mantissa}e{int(exponent)}"


def stds_text(cov: np.ndarray) -> str:
    """The standard deviations of c0, c1, c2 with their units."""
    s0, s1, s2 = np.sqrt(np.diag(cov))
    return f"{100 * s0:.1f} cm, {s1:.3g}, {number(s2)} /m"


def toml_matrix(key: str, cov: np.ndarray) -> str:
    """`key = [[...], ...]` in TOML, one row a line."""
    rows = "\n".join("  [" + ", ".join(number(v) for v in row) + "]," for row in cov)
    return f"{key} = [\n{rows}\n]"


def toml_block(pooled: Fit, per_detector: dict[str, Fit], names: list[str]) -> str:
    """The covariances as the lines to paste into estimators/closed_loop_tracker.toml: the
    pooled one as `measured_coefficient_covariance` (the R of a detector measured on its own
    nowhere, e.g. a plug-in), each detector's own in its table."""
    lines = [f"# scenarios: {' '.join(names)}",
             f"# all detectors: {pooled.count:,} detections, the {pooled.kept:.0%} core of a "
             f"robust fit; stds {stds_text(pooled.cov)}",
             toml_matrix("measured_coefficient_covariance", pooled.cov), "",
             "[measured_coefficient_covariance_by_detector]"]
    for detector, fit in per_detector.items():
        lines.append(f"# {detector}: {fit.count:,} detections, the {fit.kept:.0%} core; "
                     f"stds {stds_text(fit.cov)}")
        lines.append(toml_matrix(detector, fit.cov))
    return "\n".join(lines)
