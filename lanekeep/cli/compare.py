"""`lanekeep compare A.json B.json [--json F] [--metrics KEY ...] [--source NAME]`: is B better?

A and B are two `lanekeep bench --json` files on the same scenarios and seeds (two methods, or
before and after a change). Each (scenario, seed) is a pair; per metric the mean of B - A over
the seeds, its paired 95% interval (Student t over the per-seed differences; log ratios for
errors, given back in cm; lanekeep/scoring/statistics.py) and a verdict for B against the
metric's margin of practical relevance (docs/statistics.md#margins; `--margin` overrides):
better / worse beyond the margin, equivalent within it, non-inferior / non-superior on one
side, inconclusive when the interval reaches past both (with the smallest difference this n
could detect), too few below 3 seeds. Departures: McNemar's exact test. Errors are
lower-better; valid_share is higher-better. The "all" row is stratified: each scenario counts
once. Counts of better / worse come with Holm's adjustment and with what chance alone gives.

Exit codes: 0 compared (whatever the verdicts), 2 bad input: a missing or unreadable file, bad
JSON, not a bench document, runs on other scenarios or seeds, an unknown metric or source.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path
from typing import Any

from lanekeep.cli.outputs import error_line
from lanekeep.report.compare import (
    KEYS_HELP,
    compare_document,
    compare_runs,
    compare_table,
    metric_set,
    parse_margins,
)
from lanekeep.report.json_io import write_json

EXIT_OK, EXIT_BAD_INPUT = 0, 2


class CompareInputError(ValueError):
    """A file that cannot be read as JSON; one line naming it."""


def register(sub) -> None:
    p = sub.add_parser("compare", help="pair two bench --json runs per scenario and seed: "
                                       "B - A with 95%% intervals and verdicts for B",
                       description=__doc__, epilog=KEYS_HELP,
                       formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("a", metavar="A.json", help="the baseline: a `bench --json` file")
    p.add_argument("b", metavar="B.json", help="the candidate, judged against A: a "
                                               "`bench --json` file of the same scenarios "
                                               "and seeds")
    p.add_argument("--json", default=None, metavar="F",
                   help="also write the comparison as strict JSON (keys below)")
    p.add_argument("--metrics", nargs="+", default=None, metavar="KEY",
                   help="the metrics to compare instead of the default (fused.rmse_cm, "
                        "fused.max_cm, fused.ade_cm, fused.fde_cm, fused.valid_share, "
                        "car_rms_cm, car_max_cm, lane_departures, failed): SOURCE.FIELD or an "
                        "episode's key (car_rms_cm, mmae_switches, ...)")
    p.add_argument("--margin", action="append", default=[], metavar="[LABEL:]METRIC=ABS[,REL%]",
                   help="override a metric's margin, for every label or for one, e.g. "
                        "fused.rmse_cm=0.2,5%% or occlusion:car_max_cm=1 (cm); repeatable")
    p.add_argument("--source", action="append", default=[], metavar="NAME",
                   help="also compare this source's rmse_cm, max_cm, ade_cm, fde_cm and "
                        "valid_share (e.g. hough:track, reference); repeatable")
    p.set_defaults(func=_cmd_compare)


def read_bench(path: str) -> Any:
    """The JSON in `path`; CompareInputError naming the file if it is missing, unreadable or
    not JSON."""
    try:
        text = Path(path).read_text(encoding="utf-8")
    except FileNotFoundError:
        raise CompareInputError(f"{path}: no such file") from None
    except (OSError, UnicodeDecodeError) as err:
        raise CompareInputError(f"{path}: cannot read: {err}") from None
    try:
        return json.loads(text)
    except json.JSONDecodeError as err:
        raise CompareInputError(f"{path}: not JSON: {err}") from None


def _compare(args: argparse.Namespace) -> int:
    metrics = metric_set(args.metrics, args.source)
    margins = parse_margins(args.margin)
    result = compare_runs(read_bench(args.a), read_bench(args.b), metrics,
                          a_name=args.a, b_name=args.b, margins=margins)
    if args.json:
        try:
            write_json(args.json, compare_document(result))
        except OSError as err:
            raise CompareInputError(f"{args.json}: cannot write: {err}") from None
    print(compare_table(result))
    return EXIT_OK


def _cmd_compare(args: argparse.Namespace) -> int:
    """One line "lanekeep compare: error: ..." and exit 2 for any bad input (`--debug`:
    the exception itself)."""
    try:
        return _compare(args)
    except ValueError as err:  # IncomparableRuns, an unknown metric, CompareInputError
        if getattr(args, "debug", False):
            raise
        return error_line("compare", err)
