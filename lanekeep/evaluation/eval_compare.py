"""Two `lanekeep eval --json` documents side by side for one detector, paired over the
conditions both scored: per condition each metric of a and b, then a - b with its 95% interval
over the conditions and the verdict against the metric's declared margin
(lanekeep/scoring/statistics.py MARGINS; docs/statistics.md).

    python -m lanekeep.evaluation.eval_compare NEW.json OLD.json [--detector lanenet]
        [--json OUT.json]

The unit of pairing is a condition's set (its worlds, cameras and frames are the same in both
documents when their recipes are: the command refuses documents of different recipes). Each
set is one number per metric, so n is the number of conditions, and the verdict says whether
a is better or worse across conditions, not on any one of them.
"""

from __future__ import annotations

import argparse
import json
import math
import sys

from lanekeep.scoring.statistics import Paired, paired

# (metric, lower is better) of a detector's summary (lanekeep/evaluation/lane_metrics.py)
METRICS = (("ap", False), ("f1", False), ("iou_ego", False), ("ade_cm", True),
           ("offset_err_cm", True), ("valid", False))


class EvalMismatch(ValueError):
    """The two documents did not score the same sets."""


def _scores(doc: dict, detector: str) -> dict[str, dict]:
    out = {}
    for condition, entry in doc["conditions"].items():
        if detector in entry["detectors"]:
            out[condition] = {"set": entry["set_sha256"], **entry["detectors"][detector]}
    return out


def compare_evals(a: dict, b: dict, detector: str = "lanenet"
                  ) -> tuple[list[str], dict[str, dict], dict[str, dict], dict[str, Paired]]:
    """(conditions, a's scores, b's scores, a - b per metric) over the conditions both
    documents scored on the same set."""
    sa, sb = _scores(a, detector), _scores(b, detector)
    common = [c for c in sa if c in sb]
    if not common:
        raise EvalMismatch(f"no condition scored for {detector} in both documents")
    other = [c for c in common if sa[c]["set"] != sb[c]["set"]]
    if other:
        raise EvalMismatch(f"the sets differ for {', '.join(other)} (other recipes or renderer)")
    diffs = {m: paired([_num(sa[c][m]) for c in common], [_num(sb[c][m]) for c in common],
                       lower_is_better=low, metric=m)
             for m, low in METRICS}
    return common, sa, sb, diffs


def _num(value) -> float:
    return math.nan if value is None else float(value)


def table(common: list[str], sa: dict, sb: dict, diffs: dict[str, Paired]) -> str:
    head = f"{'condition':<13}" + "".join(f"{m:>22}" for m, _ in METRICS)
    lines = [head, f"{'':<13}" + "".join(f"{'a / b':>22}" for _ in METRICS)]
    for c in common:
        cells = "".join(f"{_fmt(sa[c][m]):>11}{_fmt(sb[c][m]):>11}" for m, _ in METRICS)
        lines.append(f"{c:<13}{cells}")
    lines.append(f"{'a - b':<13}" + "".join(f"{_fmt(diffs[m].diff):>22}" for m, _ in METRICS))
    lines.append(f"{'95% CI':<13}" + "".join(
        f"{'[' + _fmt(diffs[m].ci95[0]) + ', ' + _fmt(diffs[m].ci95[1]) + ']':>22}"
        for m, _ in METRICS))
    lines.append(f"{'margin':<13}" + "".join(f"{_fmt(diffs[m].margin):>22}" for m, _ in METRICS))
    lines.append(f"{'verdict (a)':<13}" + "".join(f"{diffs[m].verdict:>22}" for m, _ in METRICS))
    lines.append(f"n = {len(common)} conditions, paired; margins: lanekeep/scoring/statistics.py")
    return "\n".join(lines)


def _fmt(x) -> str:
    return "-" if x is None or not math.isfinite(float(x)) else f"{float(x):.3f}"


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("a", help="eval --json document (a: e.g. the new weights)")
    parser.add_argument("b", help="eval --json document (b: e.g. the old weights)")
    parser.add_argument("--detector", default="lanenet")
    parser.add_argument("--json", default=None, help="write the comparison here")
    args = parser.parse_args(argv)
    try:
        docs = [json.loads(open(p, encoding="utf-8").read()) for p in (args.a, args.b)]
        common, sa, sb, diffs = compare_evals(*docs, args.detector)
    except (OSError, ValueError, KeyError) as err:
        print(f"eval_compare: error: {err}", file=sys.stderr)
        return 2
    print(table(common, sa, sb, diffs))
    if args.json:
        from lanekeep.report.json_io import write_json

        write_json(args.json, {"a": args.a, "b": args.b, "detector": args.detector,
                               "conditions": common,
                               "paired": {m: diffs[m].as_dict(unit="") for m, _ in METRICS}})
    return 0


if __name__ == "__main__":
    sys.exit(main())
