"""Where a test run's wall time went, from a LANEKEEP_TEST_TIMELINE file (tests/conftest.py).

    LANEKEEP_TEST_TIMELINE=out/timeline.jsonl bash .ci/run
    python tools/timeline_report.py out/timeline.jsonl [--top 15]

Per worker: tests run, busy seconds, idle seconds between its tests (a wait on another
worker's shared run shows inside a test, not here) and when it finished; then the files and
tests that cost the most worker time. The wall time is the last worker's finish: with no idle
gaps only less work makes it shorter.
"""

from __future__ import annotations

import argparse
import collections
import json
import sys
from pathlib import Path


def read_timeline(path: Path) -> list[dict]:
    """The timeline's lines (worker, test, start, end), in file order."""
    return [json.loads(line) for line in path.read_text(encoding="utf-8").splitlines()
            if line.strip()]


def worker_summary(rows: list[dict]) -> dict[str, dict]:
    """Per worker: tests, busy_s, idle_s (gaps between its tests), end_s (from the first start)."""
    t0 = min(r["start"] for r in rows)
    by_worker: dict[str, list[dict]] = collections.defaultdict(list)
    for r in rows:
        by_worker[r["worker"]].append(r)
    out = {}
    for worker, runs in sorted(by_worker.items()):
        runs.sort(key=lambda r: r["start"])
        busy = sum(r["end"] - r["start"] for r in runs)
        idle = sum(max(0.0, b["start"] - a["end"]) for a, b in zip(runs, runs[1:], strict=False))
        out[worker] = {"tests": len(runs), "busy_s": busy, "idle_s": idle,
                       "end_s": runs[-1]["end"] - t0}
    return out


def costliest(rows: list[dict], by_file: bool, top: int) -> list[tuple[str, float]]:
    """The `top` files (or tests) with the most worker seconds."""
    cost: collections.Counter = collections.Counter()
    for r in rows:
        cost[r["test"].split("::")[0] if by_file else r["test"]] += r["end"] - r["start"]
    return cost.most_common(top)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("timeline", type=Path)
    parser.add_argument("--top", type=int, default=15)
    args = parser.parse_args(argv)
    try:
        rows = read_timeline(args.timeline)
    except (OSError, ValueError) as err:
        print(f"timeline_report: error: {args.timeline}: {err}", file=sys.stderr)
        return 2
    if not rows:
        print(f"timeline_report: error: {args.timeline}: no tests in it", file=sys.stderr)
        return 2
    workers = worker_summary(rows)
    total = sum(w["busy_s"] for w in workers.values())
    print(f"{len(rows)} tests, {total:.0f} worker-seconds, wall "
          f"{max(w['end_s'] for w in workers.values()):.0f} s")
    for name, w in workers.items():
        print(f"  {name:6s} {w['tests']:5d} tests  busy {w['busy_s']:6.0f} s  "
              f"idle {w['idle_s']:5.0f} s  done at {w['end_s']:6.0f} s")
    for title, by_file in (("files", True), ("tests", False)):
        print(f"costliest {title}:")
        for name, seconds in costliest(rows, by_file, args.top):
            print(f"  {seconds:7.1f} s  {100 * seconds / total:4.1f}%  {name}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
