"""Calibrate the shipped scenarios' fused-RMSE limits on tuning seeds.

    lanekeep bench --seed 1000 --seeds 5 --json tuning.json
    python tools/calibrate_criteria.py tuning.json            # the table only
    python tools/calibrate_criteria.py tuning.json --write    # and rewrite each [criteria]

Reads a `bench --seeds N --json` file run on tuning seeds (>= 1000: the bench scores 0-999, and
a limit fitted on the seeds it then judges would judge nothing) with the scenarios as shipped
(no --front-detectors, --set, --mode, --weights, --seconds), and prints per scenario the number
of seeds K, the mean and sd of the fused RMSE over them, the file's limit and the new one: the
upper 99.9% prediction bound of one new seed's RMSE, rounded up to 0.1 cm (the rule and why:
lanekeep/tuning/criteria_calibration.py). With --write each shipped scenario's block from its
"# Pass/fail" comment to the end of the file is replaced by one saying the rule, this command,
the date and the numbers, then `[criteria]` with the new max_fused_rmse_m (no departure and the
0.5 m car error are geometry, kept). Scenarios that are not shipped are shown, never written.

A file that is not such a bench, or refused by the rule: one line, exit 2.
"""

from __future__ import annotations

import argparse
import datetime
import json
import sys
from pathlib import Path

from lanekeep.scenario.schema import ScenarioError, load_scenario, shipped_scenarios
from lanekeep.tuning.criteria_calibration import (
    MAX_CAR_LATERAL_ERROR_M,
    Calibration,
    calibrate,
    check_full_length,
    criteria_block,
    geometry_note,
    rewrite_criteria,
)


class InputError(Exception):
    """A user error: one line, exit 2."""


def parse_args(argv: list[str] | None = None) -> argparse.Namespace:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("bench_json", type=Path,
                        help="the file of `lanekeep bench --seed 1000 --seeds N --json FILE`")
    parser.add_argument("--write", action="store_true",
                        help="rewrite each shipped scenario's criteria block with its new limit")
    parser.add_argument("--date", default=None, metavar="YYYY-MM-DD",
                        help="the date the block records (default: today)")
    return parser.parse_args(argv)


def _date(text: str | None) -> str:
    if text is None:
        return datetime.date.today().isoformat()
    try:
        return datetime.date.fromisoformat(text).isoformat()
    except ValueError:
        raise InputError(f"--date {text!r}: not a date YYYY-MM-DD") from None


def _load(path: Path) -> dict[str, Calibration]:
    try:
        doc = json.loads(path.read_text(encoding="utf-8"))
    except OSError as err:
        raise InputError(f"{path}: {err.strerror or err}") from None
    except (json.JSONDecodeError, UnicodeDecodeError) as err:
        raise InputError(f"{path}: not JSON ({err})") from None
    try:
        return calibrate(doc)
    except ValueError as err:
        raise InputError(f"{path}: {err}") from None


def command_of(cal: Calibration, path: Path, scenarios: list[str]) -> str:
    """The commands that make this calibration again (the bench's scenarios named unless they
    are all the shipped ones, which a bare `bench` runs)."""
    names = "" if sorted(scenarios) == shipped_scenarios() else " " + " ".join(scenarios)
    return (f"lanekeep bench{names} --seed {min(cal.seeds)} --seeds {len(cal.seeds)} "
            f"--json {path.name} && python tools/calibrate_criteria.py {path.name} --write")


def _cm(limit_m: float | None) -> str:
    return "-" if limit_m is None else f"{100.0 * limit_m:.1f}"


def run(args: argparse.Namespace) -> int:
    date = _date(args.date)
    cals = _load(args.bench_json)
    shipped = set(shipped_scenarios())
    scenarios = {}
    for name, cal in cals.items():
        if name in shipped:
            scenarios[name] = load_scenario(name)
            try:
                check_full_length(cal, scenarios[name])
            except ValueError as err:
                raise InputError(f"{args.bench_json}: {err}") from None
    width = max(8, *(len(n) for n in cals))
    print(f"{'scenario':<{width}}  {'K':>3}  {'mean cm':>8}  {'sd cm':>6}  {'old cm':>6}  "
          f"{'new cm':>6}")
    for name, cal in cals.items():
        old = scenarios[name].criteria.max_fused_rmse_m if name in scenarios else None
        note = "" if name in scenarios else "  (not shipped: never written)"
        print(f"{name:<{width}}  {len(cal.seeds):>3}  {cal.mean_cm:>8.2f}  {cal.sd_cm:>6.2f}  "
              f"{_cm(old):>6}  {_cm(cal.limit_m):>6}{note}")
        if cal.departures_max > 0 or cal.car_max_cm_max > 100.0 * MAX_CAR_LATERAL_ERROR_M:
            print(f"calibrate_criteria: warning: {name} already fails on its tuning seeds "
                  f"({cal.departures_max} departures, car max {cal.car_max_cm_max:.1f} cm)",
                  file=sys.stderr)
    if not args.write:
        return 0
    for name, scenario in scenarios.items():
        cal = cals[name]
        path = Path(scenario.source)
        block = criteria_block(cal, command_of(cal, args.bench_json, list(cals)), date,
                               geometry_note(path.read_text(encoding="utf-8")))
        try:
            rewrite_criteria(path, block)
        except (ValueError, ScenarioError) as err:
            raise InputError(str(err)) from None
        print(f"wrote {path}: max_fused_rmse_m {scenario.criteria.max_fused_rmse_m} -> "
              f"{cal.limit_m:.3f}")
    return 0


def main(argv: list[str] | None = None) -> int:
    args = parse_args(argv)
    try:
        return run(args)
    except InputError as err:
        print(f"calibrate_criteria: {err}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
