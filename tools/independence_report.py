"""Is the rear reference independent of the front sources it judges? Closed-loop episodes per
scenario and seed, each front source's and the reference's per-step errors, and per scenario
and source the verdict of lanekeep/scoring/independence.py (issue #58, paper 001).

    .venv/bin/python tools/independence_report.py                      # every shipped scenario
    .venv/bin/python tools/independence_report.py clear_curve s_bend --seeds 20 \\
        --json out/independence.json
    .venv/bin/python tools/independence_report.py --read out/independence.json  # print again
    .venv/bin/python tools/independence_report.py case1_building_shadows --seeds 3 \
        --reference-detector rowanchor    # #58's row-anchor observer as the reference

Per step: each front model's raw detection error (its offset minus the true offset at the
detector's own look-ahead, +4 m) and its Kalman track's (at the output's look-ahead), the
reference's (the offset the MMAE used, after repair, at the rear camera's look-ahead, -4 m):
the same errors `reference_error_corr` pairs (lanekeep/scoring/metrics.py); NaN where a source
had none. The curvature partialled out is the road's at the car, midway between the two look
points. `--align road` pairs instead the reference at step k with each source at the step
whose look point was the same road point (8 m earlier: ~5 steps at 15 m/s), as the MMAE's
default residual (distance_aligned) compares them, and takes the curvature there.

Seeds: the file's seed + 1 .. + N, as `lanekeep bench --seeds N`. Printed per source: the
partial correlation r pooled over the seeds with its judged 95% interval (and the plain r),
the shared bias (cm) with its interval, the co-failure lift at `--tau` with its interval and
counts (both, source, reference failures), n_eff of the steps, and PASS or why not
(IndependenceVerdict.passes: |r| interval inside 0.2, bias interval inside 1 cm, lift < 1.5).
How many seeds: with errors as autocorrelated as the issue's (phi 0.95) a 300-step episode
holds ~30 effective samples, and ~20 episodes are needed to show |r| < 0.2
(docs/statistics.md#is-the-reference-independent-of-what-it-judges).
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import math
import sys

import lanekeep  # noqa: F401  (first: it pins numpy's, torch's and OpenCV's kernels)

# isort: split
import numpy as np

from lanekeep.driver.driver import REFERENCE
from lanekeep.loop.episode import Episode
from lanekeep.loop.overrides import PluginOverrides
from lanekeep.scenario.schema import load_scenario, shipped_scenarios
from lanekeep.scoring import independence
from lanekeep.scoring.step_result import StepResult
from lanekeep.scoring.step_score import track_source
from lanekeep.scoring.truth import frenet


@dataclasses.dataclass
class Trace:
    """One episode's per-step series: errors (m, NaN = none) and look points (m of road)."""

    errors: dict[str, list[float]]
    look_s_m: dict[str, list[float]]
    car_s_m: list[float]
    car_curvature: list[float]  # 1/m, at the car
    reference_curvature: list[float]  # 1/m, at the reference's look point
    status: str = ""


def _error(estimate: float | None, truth: float) -> float:
    return math.nan if estimate is None or not math.isfinite(estimate) else estimate - truth


def run_episode(name: str, seed: int, size: tuple[int, int], seconds: float | None,
                reference: str | None = None, detectors_config: str | None = None) -> Trace:
    """Drive one episode and keep, per step, every source's error and where it looked;
    `reference`: the MMAE's reference detector instead of the scenario's; `detectors_config`:
    a detectors file in place of the scenario's `[detectors]` (as `--detectors-config`)."""
    scenario = dataclasses.replace(load_scenario(name), seed=seed)
    scenario = PluginOverrides(reference_detector=reference,
                               detectors_config=detectors_config).apply(scenario)
    with Episode(scenario, render_size=size) as episode:
        road = episode.truth.road
        models = list(episode.driver.front)
        sources = [n for m in models for n in (m, track_source(m))] + [REFERENCE]
        trace = Trace({n: [] for n in sources}, {n: [] for n in sources}, [], [], [])

        def curvature(s_m: float) -> float:
            return float(road.curvature_at(s_m % road.length_m if road.closed else s_m))

        def on_step(result: StepResult, _total: int) -> None:
            truth = result.truth
            s_car = float(frenet(road, result.sensed_pose[:2])[0])
            trace.car_s_m.append(s_car)
            trace.car_curvature.append(curvature(s_car))
            for m in models:
                e = result.estimates[m]
                looks = ((m, e.offset_m if e.valid else None, e.x_m),
                         (track_source(m), result.track_offsets_m[m], result.output_x_m))
                for source, offset, x_m in looks:
                    trace.errors[source].append(_error(offset, truth.offset_at(x_m)))
                    trace.look_s_m[source].append(s_car + x_m)
            valid = result.estimates[REFERENCE].valid
            trace.errors[REFERENCE].append(_error(result.reference_m if valid else None,
                                                  truth.offset_at(result.reference_x_m)))
            trace.look_s_m[REFERENCE].append(s_car + result.reference_x_m)
            trace.reference_curvature.append(curvature(s_car + result.reference_x_m))

        trace.status = episode.run(seconds, on_step=on_step).status
        if road.closed:  # one lap on: s keeps counting
            period = road.length_m
            unwrapped = np.unwrap(trace.car_s_m, period=period)
            shift = unwrapped - np.asarray(trace.car_s_m)
            trace.car_s_m = list(unwrapped)
            trace.look_s_m = {n: list(np.asarray(v) + shift) for n, v in trace.look_s_m.items()}
    return trace


def aligned(trace: Trace, source: str, align: str) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(e_src, e_ref, curvature) per step. "step": both as scored at the same step, curvature
    at the car. "road": the reference at step k against the source's error at the step whose
    look point lay nearest the reference's (NaN when none within half a step's travel),
    curvature at that road point."""
    e_src = np.asarray(trace.errors[source])
    e_ref = np.asarray(trace.errors[REFERENCE])
    if align == "step":
        return e_src, e_ref, np.asarray(trace.car_curvature)
    if len(e_src) < 2:
        return np.full_like(e_ref, np.nan), e_ref, np.asarray(trace.reference_curvature)
    look_src = np.maximum.accumulate(np.asarray(trace.look_s_m[source]))
    look_ref = np.asarray(trace.look_s_m[REFERENCE])
    j = np.clip(np.searchsorted(look_src, look_ref), 1, len(look_src) - 1)
    j = np.where(np.abs(look_src[j - 1] - look_ref) < np.abs(look_src[j] - look_ref), j - 1, j)
    travel = np.median(np.diff(trace.car_s_m)) if len(trace.car_s_m) > 1 else 0.0
    near = np.abs(look_src[j] - look_ref) <= max(travel / 2.0, 0.05)
    paired = np.where(near, e_src[j], np.nan)
    return paired, e_ref, np.asarray(trace.reference_curvature)


def verdict_row(v: independence.IndependenceVerdict) -> dict:
    """The verdict as a JSON object (NaN as null), with its pass and reasons."""
    ok, why = v.passes()
    return _json_safe({**v.to_dict(), "passed": ok, "reasons": list(why)})


def _json_safe(value):
    if isinstance(value, float):
        return value if math.isfinite(value) else None
    if isinstance(value, dict):
        return {k: _json_safe(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [_json_safe(v) for v in value]
    return value


def _cell(value: float | None, scale: float = 1.0, fmt: str = "+.3f") -> str:
    return "-" if value is None or not math.isfinite(value) else f"{value * scale:{fmt}}"


def row_line(source: str, row: dict) -> str:
    """One source's figures: r [interval] (plain r), bias cm [interval], lift [interval]."""
    def pair(key: str, scale: float = 1.0, fmt: str = "+.3f") -> str:
        lo, hi = row[key]
        return f"[{_cell(lo, scale, fmt)}, {_cell(hi, scale, fmt)}]"

    verdict = "PASS" if row["passed"] else "FAIL: " + "; ".join(row["reasons"])
    return (f"  {source:<18} r {_cell(row['corr'])} {pair('corr_ci95')} "
            f"(plain {_cell(row['raw_corr'])})  bias {_cell(row['shared_bias_m'], 100, '+.2f')} "
            f"{pair('shared_bias_ci95_m', 100, '+.2f')} cm  lift "
            f"{_cell(row['cofailure_lift'], 1, '.2f')} {pair('cofailure_lift_ci95', 1, '.2f')} "
            f"{tuple(row['failures'])}  n_eff {_cell(row['n_eff'], 1, '.0f')} of "
            f"{row['n_steps']}  {verdict}")


def reference_summary(traces: list[Trace]) -> dict:
    """The reference's own error over all episodes: RMSE, max and mean (its bias) in cm over
    the steps it gave an offset, the share of steps it did, and each episode's mean, RMSE and
    valid share (so that two runs over the same seeds can be paired)."""
    per = [np.asarray(t.errors[REFERENCE], dtype=float) for t in traces]
    e = np.concatenate(per)
    ok = np.isfinite(e)

    def mean_cm(v: np.ndarray) -> float:
        v = v[np.isfinite(v)]
        return float(100.0 * v.mean()) if len(v) else math.nan

    def rmse_cm(v: np.ndarray) -> float:
        v = v[np.isfinite(v)]
        return float(100.0 * np.sqrt(np.mean(v**2))) if len(v) else math.nan

    return _json_safe({"rmse_cm": float(100.0 * np.sqrt(np.mean(e[ok] ** 2))) if ok.any()
                       else math.nan,
                       "max_cm": float(100.0 * np.max(np.abs(e[ok]))) if ok.any() else math.nan,
                       "mean_cm": mean_cm(e),
                       "valid_share": float(ok.mean()) if len(e) else math.nan,
                       "steps": int(len(e)),
                       "episode_mean_cm": [mean_cm(v) for v in per],
                       "episode_rmse_cm": [rmse_cm(v) for v in per],
                       "episode_valid_share": [float(np.isfinite(v).mean()) if len(v)
                                               else math.nan for v in per]})


def report(document: dict) -> int:
    """Print a document (this tool's JSON); the number of failed verdicts."""
    s = document["settings"]
    reference = s.get("reference_detector") or "each scenario's"
    print(f"tau {s['tau_m']:g} m, align {s['align']}, {s['size']}, seconds {s['seconds']}, "
          f"reference {reference}; "
          "r: curvature partialled out; failures (both, source, reference)")
    failed = total = 0
    for name, entry in document["scenarios"].items():
        print(f"{name}: seeds {entry['seeds']} ({', '.join(entry['statuses'])})")
        ref = entry.get("reference")
        if ref:
            bias = ref.get("mean_cm")  # absent in reports before 2026-12-02
            print(f"  reference error: RMSE {_cell(ref['rmse_cm'], 1, '.2f')} cm, max "
                  f"{_cell(ref['max_cm'], 1, '.1f')} cm, mean "
                  f"{'-' if bias is None else _cell(bias, 1, '+.2f')} cm, valid "
                  f"{_cell(ref['valid_share'], 100, '.1f')}% of {ref['steps']} steps")
        for source, row in entry["sources"].items():
            print(row_line(source, row))
            total += 1
            failed += not row["passed"]
    print(f"{total - failed} of {total} sources pass")
    return failed


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("scenarios", nargs="*", help="names (default: every shipped scenario)")
    parser.add_argument("--seeds", type=int, default=20, help="the file's seed + 1 .. + N")
    parser.add_argument("--size", default="1280x720", help="render size WxH")
    parser.add_argument("--seconds", type=float, default=None, help="each episode's length")
    parser.add_argument("--tau", type=float, default=independence.TAU_M,
                        help="a failure: |error| > tau (m)")
    parser.add_argument("--align", choices=("step", "road"), default="step")
    parser.add_argument("--boots", type=int, default=independence.BOOTSTRAPS)
    parser.add_argument("--reference-detector", default=None, metavar="NAME",
                        help="the MMAE's reference instead of each scenario's (e.g. rowanchor)")
    parser.add_argument("--detectors-config", default=None, metavar="FILE",
                        help="a detectors file's settings for every scenario (e.g. a "
                             "[rowanchor] table)")
    parser.add_argument("--json", help="write the verdicts here")
    parser.add_argument("--read", help="print a JSON this tool wrote, run nothing")
    args = parser.parse_args(argv)
    if args.read:
        with open(args.read, encoding="utf-8") as f:
            report(json.load(f))
        return 0
    width, height = (int(v) for v in args.size.lower().split("x"))
    document = {"settings": {"tau_m": args.tau, "align": args.align, "size": args.size,
                             "seconds": args.seconds, "boots": args.boots,
                             "reference_detector": args.reference_detector,
                             "detectors_config": args.detectors_config},
                "scenarios": {}}
    for name in args.scenarios or shipped_scenarios():
        nominal = load_scenario(name).seed
        seeds = [nominal + k for k in range(1, args.seeds + 1)]
        traces = [run_episode(name, seed, (width, height), args.seconds, args.reference_detector,
                              args.detectors_config) for seed in seeds]
        sources = [n for n in traces[0].errors if n != REFERENCE]
        document["scenarios"][name] = {
            "seeds": seeds, "statuses": [t.status for t in traces],
            "reference": reference_summary(traces),
            "sources": {source: verdict_row(independence.independence_verdict(
                source, [aligned(t, source, args.align) for t in traces], tau_m=args.tau,
                boots=args.boots, rng=0)) for source in sources}}
        print(f"{name}: {len(seeds)} episodes done", file=sys.stderr, flush=True)
    report(document)
    if args.json:
        with open(args.json, "w", encoding="utf-8") as f:
            json.dump(document, f, indent=1)
    return 0


if __name__ == "__main__":
    sys.exit(main())
