"""Why the fused output beats or loses to a model: per-model bias, spread, MMAE weight, and
what the reference can see of them.

    MUJOCO_GL=egl python -m lanekeep.tuning.trace night [--output fused]

Runs one episode (a shipped scenario's name or a scenario file) and prints, per front model,
its own track's offset error at the output's look-ahead (RMSE, mean = bias, standard
deviation), its curvature error, and its mean MMAE probability; then the same errors of the
output and of the rear reference.

Then what the MMAE was given to tell the models apart: per model, the mean and RMS of its
residual (eq. 2: the reference minus the model's offset carried to where the reference looked),
and the correlation between the reference's error and the carried offset's error. The residual
is scored step by step, so a model whose errors rise and fall with the reference's (a positive
correlation: the same network reading the same stretch of road from the other camera) keeps a
small residual whatever its bias, and one whose errors run against the reference's pays for
both. Then each detection's left and right boundary error at the look-ahead: a bias on one
side only is the detector's (a marking lit on one side), not the lane's. Last, when the output
accrues its squared error beyond the best own track's, window by window (`--window`, s), with
the models' mean probabilities there: a loss made in the first second, before the reference
can see road the front models saw, is the prior's; one spread over the episode is the MMAE's.

Truth is read here for scoring only, as in `lanekeep run`. tools/trace_estimation.py runs the
same command line from a clone.
"""

from __future__ import annotations

import argparse
import dataclasses
import os
import sys

import numpy as np

SIDES = ("left", "right")


def trace(scenario_arg: str, output: str | None) -> tuple[list[str], dict[str, np.ndarray]]:
    """The front models' names and, per step: each model's offset and curvature errors,
    probability, MMAE residual and boundary errors, the output's and the reference's errors
    (NaN where a source had nothing)."""
    os.environ.setdefault("MUJOCO_GL", "egl")
    from lanekeep.geometry.lane_poly import LanePoly
    from lanekeep.loop.episode import Episode
    from lanekeep.scenario.schema import load_scenario
    from lanekeep.scoring.step_score import track_source
    from lanekeep.scoring.truth import lane_offsets, line_points

    scenario = load_scenario(scenario_arg)
    if output is not None:
        scenario = dataclasses.replace(
            scenario, estimation=dataclasses.replace(scenario.estimation, output=output))
    lane = scenario.road.ego_lane
    columns: dict[str, list[float]] = {}

    def add(key: str, value: float | None) -> None:
        columns.setdefault(key, []).append(np.nan if value is None else float(value))

    with Episode(scenario) as episode:
        road = episode.world.road
        names = list(episode.driver.front)

        def on_step(result, _total) -> None:
            add("time", result.time_s)
            x, y, yaw = result.sensed_pose
            s, _ = road.local_coordinates(np.array([[x, y]]))
            curvature = float(road.curvature_at(float(np.ravel(s)[0])))
            x_out = result.output_x_m
            true_sides = {side: float(line_points(road, x, y, yaw, road.boundary_r(b),
                                                  [x_out])[0, 1])
                          for side, b in zip(SIDES, (lane + 1, lane), strict=True)}
            for i, name in enumerate(names):
                track = result.tracked[name]
                offset = result.track_offsets_m[name]
                add(track_source(name), None if offset is None
                    else offset - result.truth_output_m)
                add(f"{name}:curvature", None if track is None
                    else 2.0 * track[2] - curvature)
                add(f"{name}:p", result.probabilities[i])
                add(f"{name}:residual", result.mmae_residuals_m[i])
                estimate = result.estimates[name]
                for side in SIDES:
                    coeffs = getattr(estimate, side) if estimate.valid else None
                    add(f"{name}:{side}", None if coeffs is None
                        else LanePoly.of(coeffs).y(x_out) - true_sides[side])
            centre = result.output_centre
            add("fused", None if result.output_offset_m is None
                else result.output_offset_m - result.truth_output_m)
            add("fused:curvature", None if centre is None else 2.0 * centre[2] - curvature)
            truth = lane_offsets(road, x, y, yaw, lane, [result.reference_x_m])[0]
            add("reference", None if result.reference_m is None
                else result.reference_m - float(truth))

        episode.run(on_step=on_step)
    return names, {k: np.asarray(v) for k, v in columns.items()}


def correlation(a: np.ndarray, b: np.ndarray) -> float:
    """Pearson correlation over the steps where both are finite (NaN with fewer than 3)."""
    both = np.isfinite(a) & np.isfinite(b)
    if both.sum() < 3 or np.std(a[both]) == 0 or np.std(b[both]) == 0:
        return float("nan")
    return float(np.corrcoef(a[both], b[both])[0, 1])


def residual_summary(names: list[str], columns: dict[str, np.ndarray]
                     ) -> dict[str, dict[str, float]]:
    """Per model: its residual's mean and RMS (m), and the correlation between the reference's
    error and the error of the model's offset where the reference looked (that offset is the
    reference minus the residual, so its error is the reference's error minus the residual)."""
    reference_error = columns["reference"]
    summary = {}
    for name in names:
        residual = columns[f"{name}:residual"]
        carried_error = reference_error - residual
        summary[name] = {
            "mean_m": float(np.nanmean(residual)),
            "rms_m": float(np.sqrt(np.nanmean(residual**2))),
            "correlation": correlation(reference_error, carried_error),
        }
    return summary


def excess_by_window(names: list[str], columns: dict[str, np.ndarray], track: str,
                     window_s: float) -> list[tuple[float, float, np.ndarray]]:
    """Per window of `window_s` from the first step: its start (s), the output's squared
    offset error summed over its steps minus the `track`'s (m^2; steps where either is missing
    count for neither), and the models' mean probabilities there."""
    time, fused, other = columns["time"], columns["fused"], columns[track]
    both = np.isfinite(fused) & np.isfinite(other)
    excess = np.zeros(len(time))
    excess[both] = fused[both] ** 2 - other[both] ** 2
    p = np.stack([columns[f"{name}:p"] for name in names], axis=1)
    rows = []
    start = float(time[0])
    for t0 in np.arange(start, float(time[-1]) + 1e-9, window_s):
        inside = (time >= t0) & (time < t0 + window_s)
        rows.append((float(t0), float(excess[inside].sum()), p[inside].mean(axis=0)))
    return rows


def mean_std_cm(values: np.ndarray) -> str:
    """Mean and standard deviation, cm, in two 8-wide columns."""
    return f"{100 * np.nanmean(values):+8.2f}{100 * np.nanstd(values):8.2f}"


def report(names: list[str], columns: dict[str, np.ndarray], window_s: float) -> list[str]:
    """The tables `trace`'s columns make: per source its errors, the MMAE residuals, the
    detections' boundary errors, and the output's excess over the best track per window."""
    lines = [f"{'source':<24}{'RMSE cm':>9}{'bias cm':>9}{'std cm':>8}"
             f"{'curv. RMSE 1e-3/m':>19}{'mean p':>8}"]
    sources = [k for k in columns if k.endswith(":track")] + ["fused", "reference"]
    for key in sources:
        err = columns[key]
        model = key.removesuffix(":track")
        curv = columns.get(f"{model}:curvature")
        p = columns.get(f"{model}:p")
        curv_text = "-" if curv is None else f"{1000 * np.sqrt(np.nanmean(curv ** 2)):.2f}"
        lines.append(f"{key:<24}{100 * np.sqrt(np.nanmean(err ** 2)):9.2f}"
                     f"{100 * np.nanmean(err):9.2f}{100 * np.nanstd(err):8.2f}{curv_text:>19}"
                     f"{'' if p is None else f'{np.mean(p):8.3f}'}")
    lines.append(f"\n{'MMAE residual':<24}{'mean cm':>9}{'RMS cm':>9}  corr(reference error, "
                 "model's)")
    for name, row in residual_summary(names, columns).items():
        lines.append(f"{name:<24}{100 * row['mean_m']:9.2f}{100 * row['rms_m']:9.2f}"
                     f"{row['correlation']:+9.2f}")
    lines.append(f"\n{'detection boundary':<24}{'left bias':>9}{'std':>8}{'right bias':>11}"
                 f"{'std':>8}  cm, at the output's look-ahead")
    for name in names:
        left = mean_std_cm(columns[f"{name}:left"])
        right = mean_std_cm(columns[f"{name}:right"])
        lines.append(f"{name:<24}{left} {right}")
    tracks = [k for k in columns if k.endswith(":track")]
    best = min(tracks, key=lambda k: np.nanmean(columns[k] ** 2))
    lines.append(f"\n{'from s':>6}{'excess cm2':>12}  output's squared error summed minus "
                 f"{best}'s; mean p of {', '.join(names)}")
    for t0, excess, p in excess_by_window(names, columns, best, window_s):
        lines.append(f"{t0:6.1f}{1e4 * excess:+12.2f}  " + " ".join(f"{v:.3f}" for v in p))
    return lines


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("scenario", help="a shipped scenario's name or a scenario file")
    parser.add_argument("--output", choices=("select", "fused", "precision"),
                        help="[estimation] output instead of the scenario's")
    parser.add_argument("--window", type=float, default=2.0,
                        help="seconds per row of the output's excess over the best track")
    args = parser.parse_args(argv)
    if not (np.isfinite(args.window) and args.window > 0):
        parser.error(f"--window must be a positive number of seconds, got {args.window}")
    names, columns = trace(args.scenario, args.output)
    print("\n".join(report(names, columns, args.window)))
    return 0


if __name__ == "__main__":
    sys.exit(main())
