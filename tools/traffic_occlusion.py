"""How much of the car's own lane markings the traffic hides, and what the detectors make of
those frames: closed-loop episodes of one scenario over seeds, each control period's front
frame measured against the segmentation render with and without the other vehicles.

    python tools/traffic_occlusion.py highway_cut_in --seeds 10 --json out/cut_in_occlusion.json

Per seed: the share of periods in which traffic covers more than `--threshold` of the ego
lane's paint in the front view (its two boundaries, as far as the camera sees them), and each
front detector's valid share in those periods and in the others; then the mean over seeds
with its 95% t interval, and the pooled valid shares with their exact (Clopper-Pearson)
intervals. The car drives its own loop; the measurement (two extra segmentation renders a
period) reads the simulator's truth and changes nothing it sees. Seeds: the file's seed + 1
.. + N, as `lanekeep bench --seeds N`.
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

from lanekeep.loop.episode import Episode
from lanekeep.scenario.schema import load_scenario
from lanekeep.scoring.statistics import rate_interval, spread
from lanekeep.world.traffic import occluded_marking_share


def ego_paint_hidden(episode: Episode) -> float:
    """Share of the ego lane's paint (its two boundaries) in the front view that the other
    vehicles hide (NaN when none is in view)."""
    lane = episode.world.scenario.road.ego_lane
    return occluded_marking_share(episode.world, episode.simulator.rig, "front",
                                  boundaries=(lane, lane + 1))


def run_seed(name: str, seed: int, threshold: float, size: tuple[int, int]) -> dict:
    scenario = dataclasses.replace(load_scenario(name), seed=seed)
    hidden, valid = [], {}
    with Episode(scenario, render_size=size) as episode:
        for _ in range(episode.total_steps):
            percept = episode.observe()
            share = ego_paint_hidden(episode)  # at the frames' instant
            result = episode.act()
            hidden.append(share)
            for source, estimate in result.estimates.items():
                valid.setdefault(source, []).append(bool(estimate.valid))
            del percept
            if result.off_road or result.collision:
                break
        report = episode.report(completed=not (result.off_road or result.collision))
    mask = np.asarray([(not math.isnan(h)) and h > threshold for h in hidden])
    out = {"seed": seed, "steps": len(hidden), "covered_share": float(mask.mean()),
           "hidden_mean": float(np.nanmean(hidden)) if hidden else math.nan,
           "min_ttc_s": report.min_ttc_s, "min_gap_m": report.min_gap_m,
           "collisions": report.collisions, "lane_departures": report.lane_departures,
           "car_max_cm": report.car_max_cm, "valid": {}}
    for source, flags in valid.items():
        flags = np.asarray(flags)
        out["valid"][source] = {
            "covered": [int(flags[mask].sum()), int(mask.sum())],
            "clear": [int(flags[~mask].sum()), int((~mask).sum())]}
    return out


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("scenario")
    parser.add_argument("--seeds", type=int, default=10)
    parser.add_argument("--threshold", type=float, default=0.2,
                        help="share of the ego lane's paint hidden that counts as covered")
    parser.add_argument("--size", default="1280x720", help="render size WxH")
    parser.add_argument("--json", help="write the per-seed figures here")
    args = parser.parse_args(argv)
    width, height = (int(v) for v in args.size.lower().split("x"))
    nominal = load_scenario(args.scenario).seed
    rows = []
    for k in range(1, args.seeds + 1):
        row = run_seed(args.scenario, nominal + k, args.threshold, (width, height))
        rows.append(row)
        print(f"seed {row['seed']}: covered {row['covered_share']:.3f} of {row['steps']} "
              f"periods, min TTC {row['min_ttc_s']:.2f} s, min gap {row['min_gap_m']:.2f} m, "
              f"collisions {row['collisions']}", flush=True)
    covered = spread([r["covered_share"] for r in rows])
    ttc = spread([r["min_ttc_s"] for r in rows if math.isfinite(r["min_ttc_s"] or math.inf)])
    gap = spread([r["min_gap_m"] for r in rows if r["min_gap_m"] is not None])
    print(f"\n{args.scenario}, {len(rows)} seeds (threshold {args.threshold:g} of the ego "
          f"lane's paint hidden)")
    print(f"  covered periods: mean {covered.mean:.3f} [{covered.ci95[0]:.3f}, "
          f"{covered.ci95[1]:.3f}]")
    print(f"  min TTC s: mean {ttc.mean:.2f} [{ttc.ci95[0]:.2f}, {ttc.ci95[1]:.2f}] "
          f"(n {ttc.n})")
    print(f"  min gap m: mean {gap.mean:.2f} [{gap.ci95[0]:.2f}, {gap.ci95[1]:.2f}]")
    print(f"  collisions {sum(r['collisions'] for r in rows)}, lane departures "
          f"{sum(r['lane_departures'] for r in rows)}")
    print("  valid share (pooled over seeds): covered periods | other periods")
    for source in rows[0]["valid"]:
        cells = []
        for part in ("covered", "clear"):
            k = sum(r["valid"][source][part][0] for r in rows)
            n = sum(r["valid"][source][part][1] for r in rows)
            lo, hi = rate_interval(k, n)
            cells.append(f"{k / n if n else math.nan:.3f} [{lo:.3f}, {hi:.3f}] of {n}")
        print(f"    {source:<16} {cells[0]} | {cells[1]}")
    if args.json:
        with open(args.json, "w", encoding="utf-8") as f:
            json.dump({"scenario": args.scenario, "threshold": args.threshold, "seeds": rows},
                      f, indent=1)
    return 0


if __name__ == "__main__":
    sys.exit(main())
