"""Hash every stage of an episode per step, to find the first stage at which two machines (or
two kernel settings on one machine) disagree (lanekeep/loop/stage_hashes.py).

    python tools/stage_hashes.py case4_half_shade_straight --seconds 6 --out a.jsonl
    LANEKEEP_PIN=0 python tools/stage_hashes.py case4_half_shade_straight --seconds 6 --out b.jsonl
    python tools/stage_hashes.py --compare a.jsonl b.jsonl

The settings in effect (lanekeep/core/reproducibility.py) go to stderr as one JSON line.
"""

from __future__ import annotations

import argparse
import json
import sys
from dataclasses import replace
from pathlib import Path

import lanekeep  # noqa: F401 - pins the kernels before numpy loads


def _read(path: Path) -> list[dict[str, str]]:
    return [json.loads(line) for line in path.read_text().splitlines() if line.strip()]


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("scenario", nargs="?")
    parser.add_argument("--seed", type=int)
    parser.add_argument("--seconds", type=float, default=5.0)
    parser.add_argument("--size", help="WxH render size (default: the scenario's)")
    parser.add_argument("--out", type=Path, help="JSONL file of stage hashes per step")
    parser.add_argument("--compare", nargs=2, type=Path, metavar=("A", "B"))
    args = parser.parse_args(argv)
    from lanekeep.loop.stage_hashes import first_difference, hash_episode

    if args.compare:
        a, b = (_read(p) for p in args.compare)
        where = first_difference(a, b)
        print(f"identical: {len(a)} steps, every stage" if where is None
              else f"first difference: {where}")
        return 0 if where is None else 1
    if not args.scenario or not args.out:
        parser.error("give a scenario and --out, or --compare A B")
    from lanekeep.core.reproducibility import settings_now
    from lanekeep.loop.episode import Episode
    from lanekeep.scenario.schema import load_scenario

    scenario = load_scenario(args.scenario)
    if args.seed is not None:
        scenario = replace(scenario, seed=args.seed)
    size = tuple(int(v) for v in args.size.lower().split("x")) if args.size else None
    with Episode(scenario, render_size=size) as episode:
        run = hash_episode(episode, args.seconds)
    args.out.write_text("".join(json.dumps(row) + "\n" for row in run.steps))
    print(json.dumps(settings_now()), file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
