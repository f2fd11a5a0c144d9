"""Measure the front detectors' centre-line coefficient noise in the closed loop.

    MUJOCO_GL=egl .venv/bin/python tools/measure_detector_noise.py

Measures on the tuning scenarios, every file in tools/tuning/, which `lanekeep bench` does not
score (it scores every shipped scenario, lanekeep/scenario/shipped/*.toml): tuning the tracker
on the bench's scenarios would tune it on its test set. Scenario names or files may be given
instead; a shipped scenario is refused unless --allow-scored is given.

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
window (detectors/detectors.toml [profiles.front]), so that the errors are the detectors' and
not the difference between two windows' quadratic fits of a curving road.

The code is lanekeep/tuning/detector_noise.py.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

from lanekeep.scenario.schema import load_scenario, shipped_scenarios
from lanekeep.tuning.detector_noise import Fit, errors_per_scenario, front_window, toml_block
from lanekeep.tuning.scenarios import TuningInputError, select_scenarios, shown

TUNING_DIR = Path(__file__).resolve().parent / "tuning"  # the scenarios the bench does not score


def parse_args(argv: list[str] | None = None) -> argparse.Namespace:
    """The command line; exits 2 on a shipped (bench-scored) scenario without --allow-scored."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("scenarios", nargs="*",
                        help="scenario names or files (default: every file in tools/tuning/)")
    parser.add_argument("--allow-scored", action="store_true",
                        help="allow shipped scenarios, which `lanekeep bench` scores")
    parser.add_argument("--workers", type=int, default=2, help="episodes run at a time")
    parser.add_argument("--list", action="store_true",
                        help="print the scenarios it would measure on, one a line, and stop")
    args = parser.parse_args(argv)
    try:
        args.scenarios = select_scenarios(args.scenarios, TUNING_DIR, args.allow_scored)
    except TuningInputError as err:
        parser.exit(2, f"error: {err}\n")
    return args


def main(argv: list[str] | None = None) -> None:
    args = parse_args(argv)
    if args.list:
        print("\n".join(shown(a) for a in args.scenarios))
        return
    window = front_window()
    shipped = set(shipped_scenarios())
    names = [load_scenario(arg).name for arg in args.scenarios]
    scored = [name for name in names if name in shipped]
    print(f"measuring on {len(names)} scenarios: {' '.join(shown(a) for a in args.scenarios)}")
    print("  scored by the bench: " + (", ".join(scored) if scored else "none"))
    print(f"  truth: least-squares quadratic of the road centre over x = {window[0]:g} .. "
          f"{window[1]:g} m (detectors.toml [profiles.front])")
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


if __name__ == "__main__":
    main()
