"""Soak test: an hour of closed-loop driving round a closed track, watching for leaks and drift.

    python tools/soak/soak.py [--seconds 3600] [--size 1280x720] [--json FILE]

The episode is the product's own loop (lanekeep.loop.episode.Episode) on tools/soak/loop_track.toml,
a 1134 m track that closes on itself, so the car laps it for as long as the soak lasts. Every
`--window-s` of simulated time it samples the process's resident memory (VmRSS), the median
and 95th percentile of the wall time of a control step, and checks that every number the step
produced (offsets, probabilities, steering) is finite. It passes when, after the first window
(warm-up: caches, allocator pools), memory grows by less than `--max-growth-mb`, no step held
a NaN or infinity, and the last window's median step time is within `--max-slowdown` of the
second window's. A soak is a tool, not a unit test: it takes as long as it drives.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import math
import sys
import time
from pathlib import Path

import lanekeep  # noqa: F401  (first: it pins numpy's, torch's and OpenCV's kernels)

# isort: split
import numpy as np

from lanekeep.loop.episode import Episode, StepResult
from lanekeep.scenario.schema import load_scenario

TRACK = Path(__file__).with_name("loop_track.toml")


def rss_mb() -> float:
    """Resident memory of this process (MB), from /proc (Linux)."""
    for line in Path("/proc/self/status").read_text().splitlines():
        if line.startswith("VmRSS:"):
            return int(line.split()[1]) / 1024.0
    return math.nan


def non_finite(step: StepResult) -> list[str]:
    """Names of the step's numbers that are NaN or infinite (None means "no estimate")."""
    values = {"steer": step.steer, "throttle": step.throttle,
              "truth_offset_m": step.truth_offset_m,
              "output_offset_m": step.output_offset_m, "reference_m": step.reference_m,
              **{f"track_offset_m[{k}]": v for k, v in step.track_offsets_m.items()},
              **{f"estimate[{k}].offset_m": e.offset_m for k, e in step.estimates.items()
                 if e.valid}}
    bad = [k for k, v in values.items() if v is not None and not math.isfinite(float(v))]
    if not np.all(np.isfinite(step.probabilities)):
        bad.append("probabilities")
    return bad


@dataclasses.dataclass
class Window:
    end_s: float
    rss_mb: float
    step_ms_median: float
    step_ms_p95: float
    departures: int
    non_finite_steps: int


def soak(seconds: float, size: tuple[int, int] | None, window_s: float,
         progress: bool = True) -> tuple[list[Window], dict]:
    scenario = dataclasses.replace(load_scenario(TRACK), duration_s=seconds)
    windows: list[Window] = []
    first_bad: list[str] = []
    with Episode(scenario, render_size=size) as episode:
        steps_per_window = int(round(window_s / episode.dt_s))
        total = episode.total_steps
        times, bad_steps, departures_before = [], 0, 0
        for i in range(total):
            t0 = time.perf_counter()
            result = episode.step()
            times.append(time.perf_counter() - t0)
            bad = non_finite(result)
            if bad:
                bad_steps += 1
                first_bad = first_bad or [f"step {i}: {', '.join(bad)}"]
            if (i + 1) % steps_per_window == 0 or i + 1 == total:
                departures = episode.scorer.metrics.report(scenario.name, scenario.seed,
                                                    episode.dt_s).lane_departures
                ms = 1000.0 * np.asarray(times)
                windows.append(Window((i + 1) * episode.dt_s, rss_mb(),
                                      float(np.median(ms)), float(np.percentile(ms, 95)),
                                      departures - departures_before, bad_steps))
                departures_before, times, bad_steps = departures, [], 0
                if progress:
                    w = windows[-1]
                    print(f"{w.end_s:7.0f} s  rss {w.rss_mb:7.1f} MB  step {w.step_ms_median:6.1f}"
                          f" ms (p95 {w.step_ms_p95:6.1f})  departures {w.departures}"
                          f"  non-finite steps {w.non_finite_steps}", file=sys.stderr, flush=True)
        report = episode.report()
    summary = {"laps": seconds * scenario.target_speed_mps / scenario.build_road().length_m,
               "first_non_finite": first_bad, "lane_departures": report.lane_departures,
               "fused_rmse_cm": _finite_or_none(report.sources["fused"].rmse_cm),
               "car_rms_cm": _finite_or_none(report.car_rms_cm)}
    return windows, summary


def _finite_or_none(value: float) -> float | None:
    return value if math.isfinite(value) else None


def verdict(windows: list[Window], max_growth_mb: float, max_slowdown: float) -> dict:
    """The pass criteria (module docstring) on the windows."""
    warm = windows[0].rss_mb
    growth = max(w.rss_mb for w in windows) - warm
    base = windows[1] if len(windows) > 2 else windows[0]
    slowdown = windows[-1].step_ms_median / base.step_ms_median
    finite = all(w.non_finite_steps == 0 for w in windows)
    return {"rss_growth_mb": growth, "step_slowdown": slowdown, "all_finite": finite,
            "passed": bool(growth < max_growth_mb and slowdown < max_slowdown and finite)}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--seconds", type=float, default=3600.0, help="simulated seconds")
    parser.add_argument("--size", default=None, help="render size WxH (default: the track's "
                                                     "1280x720)")
    parser.add_argument("--window-s", type=float, default=300.0,
                        help="simulated seconds per sample window")
    parser.add_argument("--max-growth-mb", type=float, default=50.0)
    parser.add_argument("--max-slowdown", type=float, default=1.2)
    parser.add_argument("--json", default=None, help="write windows and verdict as JSON")
    args = parser.parse_args(argv)
    size = tuple(int(v) for v in args.size.lower().split("x")) if args.size else None
    start = time.perf_counter()
    windows, summary = soak(args.seconds, size, args.window_s)
    result = {**summary, **verdict(windows, args.max_growth_mb, args.max_slowdown),
              "wall_s": time.perf_counter() - start, "size": args.size or "1280x720",
              "windows": [dataclasses.asdict(w) for w in windows]}
    if args.json:
        Path(args.json).write_text(json.dumps(result, indent=1, allow_nan=False) + "\n")
    print(json.dumps({k: v for k, v in result.items() if k != "windows"}, indent=1))
    return 0 if result["passed"] else 1


if __name__ == "__main__":
    sys.exit(main())
