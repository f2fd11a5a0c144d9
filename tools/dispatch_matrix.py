"""The dispatch matrix (lanekeep/loop/dispatch_matrix.py): the golden runs under every kernel
choice a CPU can lead each library to, each row as its own process.

    python tools/dispatch_matrix.py                     # every row, every golden case
    python tools/dispatch_matrix.py --quick             # the cheap rows, one case (as the tests)
    python tools/dispatch_matrix.py --markdown out.md   # the table as Markdown too
    # another checkout's code and golden files (its own venv), e.g. an older commit:
    python tools/dispatch_matrix.py --golden-tool ../old/tools/golden.py \
        --python ../old/.venv/bin/python

Exit 0 when every row is as expected (every `cpu` row identical to the golden files, every
difference named by the check), 1 otherwise, 2 on bad arguments, 3 when the golden files were
made with other library versions (nothing to compare).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
QUICK_CASE = "case4_half_shade_straight"


def main(argv: list[str] | None = None) -> int:
    from lanekeep.loop.dispatch_matrix import (
        ROWS,
        GoldenUnavailable,
        markdown_table,
        result_text,
        run_matrix,
    )

    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true",
                        help=f"the rows marked quick, on {QUICK_CASE} only")
    parser.add_argument("--only", nargs="+", metavar="SCENARIO", help="these golden cases only")
    parser.add_argument("--library", nargs="+", help="these libraries' rows only")
    parser.add_argument("--golden-tool", type=Path, default=ROOT / "tools" / "golden.py")
    parser.add_argument("--python", default=sys.executable,
                        help="the interpreter that runs the golden tool")
    parser.add_argument("--markdown", type=Path, help="also write the table here")
    args = parser.parse_args(argv)
    if not args.golden_tool.is_file():
        print(f"dispatch_matrix: error: no golden tool {args.golden_tool}", file=sys.stderr)
        return 2
    rows = [r for r in ROWS if (r.quick or not args.quick)
            and (not args.library or r.library in args.library)]
    if not rows:
        print("dispatch_matrix: error: no row matches --library", file=sys.stderr)
        return 2
    only = args.only or ([QUICK_CASE] if args.quick else [])

    def show(outcome) -> None:
        mark = "ok " if outcome.as_expected else "NO "
        print(f"{mark} {outcome.row.kind:7s} {outcome.row.library:14s} {outcome.row.setting:40s} "
              f"{result_text(outcome)}", flush=True)

    try:
        outcomes = run_matrix(rows, args.golden_tool, only, show, args.python)
    except GoldenUnavailable as why:  # another torch, OpenCV, numpy or Mesa: nothing to compare
        print(f"dispatch_matrix: {why}", file=sys.stderr)
        return 3
    table = markdown_table(outcomes)
    if args.markdown:
        args.markdown.write_text(table + "\n")
        print(f"wrote {args.markdown}", file=sys.stderr)
    bad = [o for o in outcomes if not o.as_expected]
    print(f"{len(outcomes) - len(bad)} of {len(outcomes)} rows as expected")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
