"""Check or regenerate the golden runs (lanekeep/loop/golden.py) under tests/data/golden/.

    python tools/golden.py --check            # exit 1 and the first differing stage if any
    python tools/golden.py --write            # on purpose; the commit says why they changed
    python tools/golden.py --check --only night

Exit codes: 0 identical, 1 a difference (named), 2 bad arguments, 3 the golden files were made
with other library versions (torch, OpenCV, numpy, the renderer): nothing to compare.

Run it as its own process: `import lanekeep` must come before numpy for the kernel pins to
take effect (lanekeep/core/reproducibility.py).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import lanekeep  # noqa: F401 - first: pins the kernels before numpy and torch load

FOLDER = Path(__file__).resolve().parent.parent / "tests" / "data" / "golden"


def main(argv: list[str] | None = None) -> int:
    from lanekeep.loop.golden import CASES, check, other_versions, write

    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    mode = parser.add_mutually_exclusive_group(required=True)
    mode.add_argument("--check", action="store_true")
    mode.add_argument("--write", action="store_true")
    parser.add_argument("--only", nargs="+", metavar="SCENARIO",
                        help="these golden cases only (default: all)")
    parser.add_argument("--folder", type=Path, default=FOLDER)
    args = parser.parse_args(argv)
    names = [c.scenario for c in CASES]
    unknown = [n for n in args.only or [] if n not in names]
    if unknown:
        print(f"golden: error: no golden case {', '.join(unknown)} (cases: {', '.join(names)})",
              file=sys.stderr)
        return 2
    cases = tuple(c for c in CASES if not args.only or c.scenario in args.only)
    if args.write:
        for path in write(args.folder, cases):
            print(path)
        return 0
    versions = other_versions(args.folder, cases)
    if versions:
        print("golden: the golden files were made with other library versions: "
              + "; ".join(versions) + ". Their bits cannot be compared here; make them anew "
              "on purpose (--write) where these versions are the project's.", file=sys.stderr)
        return 3
    failed = 0
    for scenario, problems in check(args.folder, cases).items():
        print(f"{scenario}: {'identical' if not problems else 'DIFFERS'}")
        for problem in problems:
            print(f"  {problem}")
        failed += bool(problems)
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
