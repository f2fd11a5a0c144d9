"""`lanekeep eval`: every detector on the fixed test sets of every condition; table and JSON.

    lanekeep eval [--detectors hough,sliding_window,lanenet] [--weights FILE] [--json FILE]
                  [--detectors-config FILE]
                  [--quick] [--frames N] [--stateless] [--split test|tuning] [--cache DIR]
                  [--conditions clear,night,...]

Thin: the sets, the scoring loop, the table and the JSON document are
lanekeep/evaluation/detector_eval.py's (the sets lanekeep/evaluation/eval_sets.py's, the metrics
lanekeep/evaluation/lane_metrics.py's).
Bad input (an unknown detector or condition, an unreadable weights file or detectors file, an
output that cannot be written) is one "lanekeep eval: error:" line and exit 2, before anything
is rendered.
"""

from __future__ import annotations

import argparse
import dataclasses
import sys

from lanekeep.cli.outputs import error_line
from lanekeep.evaluation.detector_eval import DEFAULT_DETECTORS, BadInput, evaluate, table

EXIT_OK, EXIT_BAD_INPUT = 0, 2


def cmd_eval(args: argparse.Namespace) -> int:
    from lanekeep.evaluation.detector_eval import eval_document, plan_eval
    from lanekeep.evaluation.eval_sets import EvalRecipe
    from lanekeep.report.json_io import write_json

    try:
        if args.frames is not None and args.frames < 1:
            raise BadInput(f"--frames must be at least 1, got {args.frames}")
        plan = plan_eval(args.detectors, args.conditions, args.weights, args.json, args.cache,
                         args.detectors_config)
    except BadInput as err:
        if getattr(args, "debug", False):
            raise
        return error_line("eval", err)
    recipe = EvalRecipe.quick() if args.quick else EvalRecipe()
    if args.frames is not None:
        recipe = dataclasses.replace(recipe, frames=args.frames)
    recipe = dataclasses.replace(recipe, split=args.split)
    results = evaluate(plan.conditions, plan.detectors, plan.weights, recipe, args.cache or None,
                       progress=lambda m: print(m, file=sys.stderr, flush=True),
                       stateless=args.stateless, config=plan.config)
    print(table(results))
    if args.json:
        write_json(args.json, eval_document(plan, recipe, args.quick, results, args.stateless))
        print(f"wrote {args.json}")
    return EXIT_OK


def register(subparsers) -> None:
    p = subparsers.add_parser(
        "eval", help="score detectors on fixed rendered test sets per condition (AP, IoU, "
                     "ADE/FDE, offset error, ms)",
        description="Renders (once; then read from --cache) a fixed test set per condition "
                    "and scores each detector on it; metrics are defined in "
                    "lanekeep/evaluation/lane_metrics.py.")
    p.add_argument("--detectors", default=DEFAULT_DETECTORS,
                   help=f"comma-separated detector names (default {DEFAULT_DETECTORS})")
    p.add_argument("--conditions", default="all",
                   help="comma-separated conditions (default: all): clear, curve, buildings, "
                        "half_shade, night, rain, fog, snow, worn, occlusion_40, occlusion_60, "
                        "dots")
    p.add_argument("--weights", metavar="FILE", default=None,
                   help="LaneNet weights (default: the shipped detectors/weights/lanenet.pt)")
    p.add_argument("--detectors-config", metavar="FILE", default=None,
                   help="a detectors TOML file (the keys of detectors/detectors.toml, e.g. "
                        "[hough] binarisation = \"ridge\", [lanenet] width_std_m = 0.3) that "
                        "the detectors run with instead of the shipped settings (recorded in "
                        "--json)")
    p.add_argument("--json", metavar="FILE", default=None, help="write the results as JSON")
    p.add_argument("--quick", action="store_true",
                   help="one world and one sequence per condition (tests, smoke runs)")
    p.add_argument("--frames", type=int, metavar="N", default=None,
                   help="frames per sequence (default: the sets' own, EvalRecipe.frames in "
                        "lanekeep/evaluation/eval_sets.py); each detector keeps "
                        "its state across a sequence, so longer ones let LaneNet's recurrent "
                        "part matter (sets of another length are other sets)")
    p.add_argument("--stateless", action="store_true",
                   help="reset each detector before every frame, not only before each sequence: "
                        "what it gives without its memory of earlier frames (LaneNet without "
                        "its recurrent state: the frame-only ablation on the same frames)")
    p.add_argument("--split", choices=("test", "tuning"), default="test",
                   help="which worlds: test (default), the scored sets; tuning, other worlds of "
                        "every condition to choose settings on (never on the scored ones)")
    p.add_argument("--cache", metavar="DIR", default="out/eval_cache",
                   help="folder of rendered sets (default out/eval_cache; '' = no cache)")
    p.set_defaults(func=cmd_eval)
