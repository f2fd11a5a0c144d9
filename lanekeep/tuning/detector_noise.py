"""Measure the front detectors' centre-line coefficient noise in the closed loop.

    MUJOCO_GL=egl python -m lanekeep.tuning.detector_noise

Measures on the tuning scenarios, every file in lanekeep/tuning/scenario_files/, which
`lanekeep bench` does not score (it scores every shipped scenario,
lanekeep/scenario/shipped/*.toml): tuning the tracker on the bench's scenarios would tune it on
its test set. Scenario names or files may be given instead; a shipped scenario is refused
unless --allow-scored is given.

Runs each scenario's episode (`--workers` at a time), collects every valid detection's centre
line [c0, c1, c2] minus the true centre line at the pose its frame was taken from, per front
detector, and prints per detector and for all of them together the covariance of the errors'
core (an iterated 97.5% chi-square trim, which keeps ~80%: the tails are heavy) and the share
of detections a tracker gate would reject with it, then the result as the TOML to paste into
estimators/closed_loop_tracker.toml: the pooled covariance as `measured_coefficient_covariance`
(the R of a detector measured on its own nowhere, e.g. a plug-in) and each detector's own in
`[measured_coefficient_covariance_by_detector]`. Detectors differ (at 4 m ahead the learned
one's lateral std is 0.64 cm, the classical ones' 1.3-2.1; at 20 m it is the noisiest), and a
track whose R is its detector's follows a good detector without lag and smooths a noisy one. The
truth is the least-squares quadratic of the exact road centre over the front detectors' own fit
window (detectors/config.py profiles.front), so that the errors are the detectors' and
not the difference between two windows' quadratic fits of a curving road.

tools/measure_detector_noise.py runs the same command line from a clone.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from scipy.stats import chi2

from lanekeep.core.workers import set_thread_counts, worker_pool
from lanekeep.scenario.schema import load_scenario, shipped_scenarios
from lanekeep.tuning.scenarios import (
    TuningInputError,
    add_scenario_arguments,
    select_scenarios,
    shown,
)


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


def parse_args(argv: list[str] | None = None) -> argparse.Namespace:
    """The command line; exits 2 on a shipped (bench-scored) scenario without --allow-scored."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    add_scenario_arguments(parser)
    parser.add_argument("--workers", type=int, default=2, help="episodes run at a time")
    parser.add_argument("--list", action="store_true",
                        help="print the scenarios it would measure on, one a line, and stop")
    args = parser.parse_args(argv)
    try:
        args.scenarios = select_scenarios(args.scenarios, allow_scored=args.allow_scored)
    except TuningInputError as err:
        parser.exit(2, f"error: {err}\n")
    return args


def main(argv: list[str] | None = None) -> int:
    args = parse_args(argv)
    if args.list:
        print("\n".join(shown(a) for a in args.scenarios))
        return 0
    window = front_window()
    shipped = set(shipped_scenarios())
    names = [load_scenario(arg).name for arg in args.scenarios]
    scored = [name for name in names if name in shipped]
    print(f"measuring on {len(names)} scenarios: {' '.join(shown(a) for a in args.scenarios)}")
    print("  scored by the bench: " + (", ".join(scored) if scored else "none"))
    print(f"  truth: least-squares quadratic of the road centre over x = {window[0]:g} .. "
          f"{window[1]:g} m (detectors/config.py profiles.front)")
    per_detector: dict[str, list[np.ndarray]] = {}
    jobs = errors_per_scenario(args.scenarios, window, args.workers)
    for name, errors in zip(names, jobs, strict=True):
        counts = ", ".join(f"{d} {len(e)}" for d, e in errors.items())
        print(f"  {name}: {counts} detections", flush=True)
        for detector, rows in errors.items():
            per_detector.setdefault(detector, []).extend(rows)
    np.set_printoptions(precision=3, suppress=False)
    arrays = {d: np.array(rows) for d, rows in per_detector.items()}
    fits = {d: Fit.of(e) for d, e in arrays.items()}
    for detector, fit in fits.items():
        print("\n".join(fit.report(detector, arrays[detector])))
    everything = np.concatenate(list(arrays.values()))
    pooled = Fit.of(everything)
    print("\n".join(pooled.report("all detectors", everything)))
    print("\nTOML (estimators/closed_loop_tracker.toml):")
    print(toml_block(pooled, fits, names))
    sys.stdout.flush()
    return 0


if __name__ == "__main__":
    sys.exit(main())
