"""Paper 001's Tables 3-4 and its two patterns, reproduced in paper mode over seeds (#58).

    MUJOCO_GL=egl .venv/bin/python tools/paper_tables.py --seeds 10 --json out/paper_tables.json
    MUJOCO_GL=egl .venv/bin/python tools/paper_tables.py --read out/paper_tables.json
    MUJOCO_GL=egl .venv/bin/python tools/paper_tables.py case2_sharp_turn --seeds 3 \\
        --keep binarisation          # one of our deviations kept (docs/paper_mode.md)
    MUJOCO_GL=egl .venv/bin/python tools/paper_tables.py case2_sharp_turn --seeds 10 \\
        --open-loop                  # the paper's models on the frames of a drive in lane
    MUJOCO_GL=egl .venv/bin/python tools/paper_tables.py case1_building_shadows --seeds 10 \\
        --set 'conditions.shadows[0].coverage=1.0' \\
        --detectors-config F.toml    # a scenario key and a detectors file for every case

Each paper case runs in paper mode (`[estimation] mode = "paper"`) at seeds file + 1 .. + N (as
`lanekeep bench --seeds N`). Scored as the paper scores (lanekeep/scoring/paper_tables.py):
every offset at the car, RMSE over every step with the value the loop carries. Printed per
case: model #1, model #2, the final offset and the observer, mean over seeds with its 95%
interval, beside the paper's Table 3 (case 2) and Table 4 (case 4); the patterns as paired
verdicts over the seeds (lanekeep/scoring/statistics.py); and each model's share of steps with
a value of its own, in the event and outside it:

* case 1 (building shadows): in the shaded steps model #1 worse than model #2, and the share of
  those steps the MMAE is on model #2;
* case 2 (sharp turn): model #2 worse than model #1, their ratio, and the share of the turn's
  steps the MMAE is on model #1 (the paper: model #1 "between time step 10 and 70").

Event steps: the point 4 m ahead in a cast shadow (cases 1, 3, 4), or the road's curvature there
above 0.01 1/m (cases 2, 5). Truth is read here, on the scoring side only.
"""

from __future__ import annotations

import argparse
import json
import multiprocessing
import sys
from concurrent.futures import ProcessPoolExecutor
from dataclasses import replace
from pathlib import Path

import lanekeep  # noqa: F401  (first: it pins numpy's, torch's and OpenCV's kernels)

# isort: split
import numpy as np

from lanekeep.geometry.lane_poly import LanePoly
from lanekeep.scoring import statistics as stats
from lanekeep.scoring.paper_tables import COLUMNS, PAPER_TABLES, PaperTrace, paper_row

PAPER_CASES = ("case1_building_shadows", "case2_sharp_turn", "case3_mild_turn_shade_bumps",
               "case4_half_shade_straight", "case5_wet_rain_turn")
EVENTS = {"case1_building_shadows": "shade", "case2_sharp_turn": "turn",
          "case3_mild_turn_shade_bumps": "shade", "case4_half_shade_straight": "shade",
          "case5_wet_rain_turn": "turn"}
TURN_CURVATURE = 0.01  # 1/m: the 40 m arc of case 2 and the steep ends of its clothoids


def run_one(name: str, seed: int, keeps: tuple[str, ...], open_loop: bool = False,
            overrides=None) -> dict:
    """One episode of a paper case, scored as the paper scores: in paper mode, or with
    `open_loop` driven by the default loop while the paper's two models (paper mode's
    detectors, less `keeps`) read the same front frames beside it (`open_loop_models`).
    `overrides`: the command line's `--detectors-config` and `--set` (a PluginOverrides,
    lanekeep/loop/overrides.py), applied as `lanekeep bench` applies them, after the mode and
    the seed."""
    from lanekeep.loop.episode import Episode
    from lanekeep.loop.paper_mode import with_mode
    from lanekeep.scenario.schema import load_scenario

    if open_loop:  # the default loop drives; `keeps` reach the two models only
        scenario = replace(load_scenario(name), seed=seed)
    else:
        scenario = with_mode(load_scenario(name), "paper")
        scenario = replace(scenario, seed=seed,
                           estimation=replace(scenario.estimation, paper_keeps=keeps))
    if overrides is not None:
        scenario = overrides.apply(scenario)
    trace = PaperTrace()
    with Episode(scenario) as episode:
        road, conditions = episode.world.road, episode.world.conditions
        estimator = episode.driver.estimator
        models = open_loop_models(episode, keeps) if open_loop else None
        labels = list(models or episode.driver.front)
        held: list[float | None] = [None] * len(labels)

        def on_step(step, total):
            x, y, yaw = step.sensed_pose
            s, _ = road.local_coordinates(np.array([x, y]))
            if EVENTS[name] == "shade":
                ahead = np.array([x + 4.0 * np.cos(yaw), y + 4.0 * np.sin(yaw)])
                in_event = bool(conditions.shaded(ahead))
            else:
                in_event = abs(float(road.curvature_at(float(s) + 4.0))) > TURN_CURVATURE
            estimates = ({label: model.detect(step.frames["front"])
                          for label, model in models.items()} if models else step.estimates)
            offsets: dict[str, float | None] = {}
            for i, label in enumerate(labels[:2]):
                centre = estimator.centre_of(estimates[label])
                value = None if centre is None else float(LanePoly.of(centre).offset_m(0.0))
                offsets[f"model{i + 1}"] = value
                if value is not None:
                    held[i] = value
            if models:  # no paper MMAE ran: no final offset, no selection
                offsets["final"], selected = None, -1
            else:
                offsets["final"] = held[step.selected] if step.selected < 2 else None
                selected = step.selected
            offsets["observer"] = step.reference_m
            trace.add(step.truth.offset_at(0.0), offsets, selected, in_event)

        report = episode.run(on_step=on_step)
    row = paper_row(trace).to_dict()
    row.update(case=name, seed=seed, departures=report.lane_departures,
               completed=report.completed, open_loop=open_loop)
    return row


def open_loop_models(episode, keeps: tuple[str, ...]) -> dict:
    """The paper's model #1 (hough) and model #2 (sliding_window) as paper mode builds them
    (its windows and fixed thresholds, less `keeps`), on the episode's front camera; they
    keep their own state across the drive and steer nothing. Why: in paper mode the paper's
    PID loses the lane in case 2 and every model then errs; driven by the default loop, which
    keeps the lane, the two models are compared on the frames of a drive that stays in it."""
    from lanekeep.detectors.registry import make_detector
    from lanekeep.driver.paper_mode import front_detector_config

    config = episode.driver.config
    camera, lens = config.cameras["front"], config.distortions.get("front")
    models = {name: make_detector(name, camera,
                                  front_detector_config(name, "paper", config.detectors, keeps),
                                  lens)
              for name in ("hough", "sliding_window")}
    for model in models.values():
        model.reset()
    return models


def _interval(spread: stats.Spread, fmt: str) -> str:
    lo, hi = spread.ci95
    return f"{spread.center:{fmt}} [{lo:{fmt}}, {hi:{fmt}}]"


def _verdict(a: list[float], b: list[float]) -> str:
    """a - b paired over the seeds, with the RMSE margin (lanekeep/scoring/statistics.py)."""
    p = stats.paired(a, b, metric="rmse_cm")
    lo, hi = p.ci95
    return (f"{p.diff:+.2f} cm [{lo:+.2f}, {hi:+.2f}] (margin {p.margin:.2f}, n {p.n}): "
            f"{p.verdict}")


def summarise(rows: list[dict]) -> str:
    """The tables and the pattern verdicts, per case."""
    lines = []
    for name in PAPER_CASES:
        case = [r for r in rows if r["case"] == name]
        if not case:
            continue
        lines.append(f"\n{name}: {len(case)} seeds, departures "
                     f"{sum(r['departures'] for r in case)}, event = {EVENTS[name]} "
                     f"(mean {np.mean([r['event_steps'] for r in case]):.0f} of "
                     f"{np.mean([r['steps'] for r in case]):.0f} steps)")
        paper = PAPER_TABLES.get(name, {})
        lines.append("| | " + " | ".join(COLUMNS) + " |")
        lines.append("|---" * (len(COLUMNS) + 1) + "|")
        for label, key in (("ours, RMSE cm", "rmse_cm"), ("ours in the event", "event_rmse_cm")):
            cells = []
            for column in COLUMNS:
                cells.append(_interval(stats.spread([r[key][column] for r in case],
                                                    log_scale=True), ".1f"))
            lines.append(f"| {label} | " + " | ".join(cells) + " |")
        if paper:
            lines.append("| paper | " + " | ".join(f"{paper[c]:.2f}" for c in COLUMNS) + " |")
        m1 = [r["rmse_cm"]["model1"] for r in case]
        m2 = [r["rmse_cm"]["model2"] for r in case]
        e1 = [r["event_rmse_cm"]["model1"] for r in case]
        e2 = [r["event_rmse_cm"]["model2"] for r in case]
        on1 = stats.spread([r["selected_share_in_event"][0] for r in case])
        on2 = stats.spread([r["selected_share_in_event"][1] for r in case])
        lines.append(f"model #2 - model #1 over the drive: {_verdict(m2, m1)}")
        lines.append(f"model #2 - model #1 in the event:  {_verdict(e2, e1)}")
        ratio = stats.spread([b / a for a, b in zip(m1, m2, strict=True) if a > 0],
                             log_scale=True)
        selection = ("no paper MMAE (open loop)" if any(r.get("open_loop") for r in case)
                     else f"MMAE on model #1 in the event {_interval(on1, '.2f')}, on model "
                     f"#2 {_interval(on2, '.2f')}")
        lines.append(f"model #2 / model #1 (geometric mean): {_interval(ratio, '.2f')}; "
                     f"{selection}")
        if all("valid_share_in_event" in r for r in case):  # rows from before 2026-12-01: none
            valid = [stats.spread([r[key][i] for r in case]) for key in
                     ("valid_share_in_event", "valid_share_outside") for i in (0, 1)]
            lines.append(f"a value of its own: model #1 in the event {_interval(valid[0], '.2f')}, "
                         f"outside {_interval(valid[2], '.2f')}; model #2 in the event "
                         f"{_interval(valid[1], '.2f')}, outside {_interval(valid[3], '.2f')}")
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("cases", nargs="*", default=list(PAPER_CASES))
    parser.add_argument("--seeds", type=int, default=10)
    parser.add_argument("--keep", action="append", default=[],
                        help="a deviation of ours to keep in paper mode (repeatable)")
    parser.add_argument("--open-loop", action="store_true",
                        help="drive with the default loop and run the paper's two models beside "
                        "it on the same front frames (no paper MMAE: final and shares are nan)")
    parser.add_argument("--detectors-config", metavar="FILE",
                        help="a detectors TOML file that becomes each case's [detectors] table "
                        "(e.g. [paper] white_level = 125), recorded in --json")
    parser.add_argument("--set", dest="settings", action="append", default=[],
                        metavar="KEY=VALUE", help="a scenario key for every case, as `lanekeep "
                        "bench --set` (e.g. 'conditions.shadows[0].coverage=1.0'), recorded")
    parser.add_argument("--workers", type=int, default=1)
    parser.add_argument("--json", type=Path, help="write the rows here")
    parser.add_argument("--read", type=Path, help="print the rows of an earlier --json")
    args = parser.parse_args(argv)
    if args.read:
        try:
            rows = json.loads(args.read.read_text())["rows"]
        except (OSError, ValueError, KeyError, TypeError) as err:
            print(f"error: {args.read} is not a paper_tables.py --json file ({err})",
                  file=sys.stderr)
            return 2
        print(summarise(rows))
        return 0
    if args.seeds < 1 or args.workers < 1:
        print("error: --seeds and --workers must be at least 1", file=sys.stderr)
        return 2
    unknown = [c for c in args.cases if c not in PAPER_CASES]
    if unknown:
        print(f"error: not a paper case: {unknown[0]} (one of {', '.join(PAPER_CASES)})",
              file=sys.stderr)
        return 2
    from lanekeep.core.config_io import ConfigError
    from lanekeep.loop.overrides import PluginOverrides
    from lanekeep.scenario.keys import parse_setting
    from lanekeep.scenario.schema import ScenarioError, load_scenario

    try:
        settings = tuple(parse_setting(text) for text in args.settings)
    except ValueError as err:
        print(f"error: --set: {err}", file=sys.stderr)
        return 2
    overrides = PluginOverrides(settings=settings, detectors_config=args.detectors_config)
    try:  # a bad file or a key a case cannot take: one line, before any episode
        overrides.check()
        for name in args.cases:
            overrides.apply(load_scenario(name))
    except (ConfigError, ScenarioError) as err:
        print(f"error: {err}", file=sys.stderr)
        return 2
    jobs = [(name, load_scenario(name).seed + k, tuple(args.keep), args.open_loop, overrides)
            for name in args.cases for k in range(1, args.seeds + 1)]
    if args.workers > 1:
        context = multiprocessing.get_context("spawn")
        with ProcessPoolExecutor(args.workers, mp_context=context) as pool:
            rows = list(pool.map(run_one, *zip(*jobs, strict=True)))
    else:
        rows = []
        for job in jobs:
            rows.append(run_one(*job))
            print(f"{job[0]} seed {job[1]}: " + ", ".join(
                f"{c} {rows[-1]['rmse_cm'][c]:.1f}" for c in COLUMNS), flush=True)
            if args.json:  # kept as it grows: an interrupted run loses only its last episode
                args.json.write_text(json.dumps({"keeps": args.keep, "open_loop": args.open_loop,
                                             "detectors_config": args.detectors_config,
                                             "settings": args.settings, "rows": rows},
                                            indent=1))
    if args.json:
        args.json.write_text(json.dumps({"keeps": args.keep, "open_loop": args.open_loop,
                                         "detectors_config": args.detectors_config,
                                         "settings": args.settings, "rows": rows}, indent=1))
    print(summarise(rows))
    return 0


if __name__ == "__main__":
    sys.exit(main())
