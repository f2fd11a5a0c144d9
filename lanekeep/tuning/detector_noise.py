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

Each detector's detections are also cut at the quintiles of their own confidence into bands,
and each band's core covariance is given as a factor of the detector's (the cube root of the
ratio of determinants), with the share of its detections over 30 cm off 4 m ahead: the
`[confidence_noise_by_detector]` table of estimators/closed_loop_tracker.toml, which
`[estimation] confidence_noise` uses (estimators/confidence.py).

tools/measure_detector_noise.py runs the same command line from a clone.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Iterator, Sequence
from dataclasses import dataclass, field
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


@dataclass
class Detections:
    """One front detector's valid detections of an episode: each one's coefficients minus the
    truth's, and its own confidence."""

    errors: list[np.ndarray] = field(default_factory=list)
    confidences: list[float] = field(default_factory=list)

    def extend(self, other: Detections) -> None:
        self.errors.extend(other.errors)
        self.confidences.extend(other.confidences)


def coefficient_errors(name: str | Path, fit_range_m: tuple[float, float]
                       ) -> dict[str, Detections]:
    """Per front detector, detection minus truth and the detection's confidence, one row per
    valid detection of one episode."""
    from lanekeep.loop.episode import Episode
    from lanekeep.scoring.truth import lane_truth

    scenario = load_scenario(name)
    found: dict[str, Detections] = {}
    with Episode(scenario) as episode:
        for _ in range(episode.total_steps):
            step = episode.step()
            truth = lane_truth(episode.world.road, *step.sensed_pose, scenario.road.ego_lane,
                               fit_range_m=fit_range_m).center
            for detector in episode.driver.front:
                estimate = step.estimates[detector]
                centre = episode.driver.estimator.centre_of(estimate)
                if centre is not None:
                    rows = found.setdefault(detector, Detections())
                    rows.errors.append(np.asarray(centre) - truth)
                    rows.confidences.append(float(estimate.confidence))
    return found


def errors_per_scenario(scenarios: Sequence[str], fit_range_m: tuple[float, float],
                        workers: int) -> Iterator[dict[str, Detections]]:
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


@dataclass(frozen=True)
class BandFit:
    """One band of a detector's confidence: its detections' count, the factor of the
    detector's R its core covariance is (the cube root of the determinants' ratio: the
    geometric mean over the principal axes), and the share of its detections over 30 cm off
    at the output's look-ahead (a wrong line, which no Gaussian R describes)."""

    low: float
    high: float
    count: int
    scale: float
    std_4m_m: float
    gross_share: float


LOOKAHEAD_ROW = np.array([1.0, 4.0, 16.0])  # the lane's lateral position 4 m ahead
GROSS_M = 0.30


def confidence_bands(found: Detections, overall: Fit, count: int = 5) -> list[BandFit]:
    """The detections cut at the quantiles of their confidence into `count` bands (edges
    rounded to 0.01; tied edges merged), each band's core against the detector's."""
    errors, confidences = np.array(found.errors), np.array(found.confidences)
    quantiles = np.quantile(confidences, np.arange(1, count) / count)
    edges = np.unique(np.round(quantiles, 2))
    band = np.searchsorted(edges, confidences, side="right")
    bounds = [-np.inf, *edges, np.inf]
    fits = []
    for k in range(len(edges) + 1):
        rows = errors[band == k]
        if len(rows) < 10 * rows.shape[1]:
            raise ValueError(f"confidence band {k} holds only {len(rows)} detections")
        _, cov, _ = core_covariance(rows)
        scale = float(np.cbrt(np.linalg.det(cov) / np.linalg.det(overall.cov)))
        lateral = np.abs(rows @ LOOKAHEAD_ROW)
        fits.append(BandFit(float(bounds[k]), float(bounds[k + 1]), len(rows), scale,
                            float(np.sqrt(LOOKAHEAD_ROW @ cov @ LOOKAHEAD_ROW)),
                            float(np.mean(lateral > GROSS_M))))
    return fits


def bands_report(detector: str, bands: list[BandFit]) -> list[str]:
    """Per band: the confidence range, the count, the factor of R, the core's lateral std 4 m
    ahead and the share of gross errors."""
    lines = [f"{detector}, by confidence band (factor of R; core std 4 m ahead; share over "
             f"{100 * GROSS_M:.0f} cm off there):"]
    for band in bands:
        lines.append(f"  [{band.low:.2f}, {band.high:.2f}): {band.count} detections, factor "
                     f"{band.scale:.2f}, std {100 * band.std_4m_m:.1f} cm, "
                     f"{band.gross_share:.1%} gross")
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


def toml_bands(per_detector: dict[str, list[BandFit]]) -> str:
    """The confidence bands as the lines to paste into estimators/closed_loop_tracker.toml."""
    lines = ["[confidence_noise_by_detector]"]
    for detector, bands in per_detector.items():
        edges = ", ".join(f"{band.low:g}" for band in bands[1:])
        scales = ", ".join(f"{band.scale:.2f}" for band in bands)
        gross = ", ".join(f"{band.gross_share:.1%}" for band in bands)
        lines.append(f"# {detector}: {sum(b.count for b in bands):,} detections; gross "
                     f"errors by band {gross}")
        lines.append(f"{detector} = {{ edges = [{edges}], scales = [{scales}] }}")
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
    per_detector: dict[str, Detections] = {}
    jobs = errors_per_scenario(args.scenarios, window, args.workers)
    for name, found in zip(names, jobs, strict=True):
        counts = ", ".join(f"{d} {len(rows.errors)}" for d, rows in found.items())
        print(f"  {name}: {counts} detections", flush=True)
        for detector, rows in found.items():
            per_detector.setdefault(detector, Detections()).extend(rows)
    np.set_printoptions(precision=3, suppress=False)
    arrays = {d: np.array(rows.errors) for d, rows in per_detector.items()}
    fits = {d: Fit.of(e) for d, e in arrays.items()}
    bands = {}
    for detector, fit in fits.items():
        print("\n".join(fit.report(detector, arrays[detector])))
        try:
            bands[detector] = confidence_bands(per_detector[detector], fit)
        except ValueError as err:  # too few detections to cut into bands
            print(f"{detector}: no confidence bands ({err})")
            continue
        print("\n".join(bands_report(detector, bands[detector])))
    everything = np.concatenate(list(arrays.values()))
    pooled = Fit.of(everything)
    print("\n".join(pooled.report("all detectors", everything)))
    print("\nTOML (estimators/closed_loop_tracker.toml):")
    print(toml_block(pooled, fits, names))
    print()
    print(toml_bands(bands))
    sys.stdout.flush()
    return 0


if __name__ == "__main__":
    sys.exit(main())
