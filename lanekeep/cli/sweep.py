"""`lanekeep sweep FILE [--workers N] [--ray [ADDRESS]] [--out DIR]`: a grid of episodes.

The sweep file (lanekeep/sweep/spec.py) expands to cells; they run in local worker processes
(default) or as Ray tasks (`--ray`: a local Ray, or the cluster at ADDRESS), each finished cell
written down at once (lanekeep/sweep/store.py). An `--out` folder that already holds this
sweep resumes it: finished cells are skipped, failed ones run again. At the end:
results.parquet, summary.json and plots/*.png (lanekeep/sweep/plots.py) in the folder.

Exit codes: 0 every cell ran (whatever its metrics), 1 some cell failed (raised), 2 bad input,
130 interrupted (the finished cells are kept; run the same command again to resume).
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

from lanekeep.core.config_io import ConfigError


def register(sub) -> None:
    p = sub.add_parser("sweep", help="run a grid of episodes over scenario parameters "
                                     "(local workers or Ray); resumable; Parquet + plots",
                       description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("file", help="sweep file (.toml): base scenario, parameters, seeds, metrics")
    p.add_argument("--workers", type=int, default=None,
                   help="local worker processes (default 2); with a local --ray, its CPUs")
    p.add_argument("--ray", nargs="?", const="", default=None, metavar="ADDRESS",
                   help="run the cells as Ray tasks: a local Ray without ADDRESS, else the "
                        "cluster's (e.g. HEAD:6379 or auto); needs lanekeep[ray]")
    p.add_argument("--out", default=None,
                   help="output folder (default out/sweeps/NAME); one holding this sweep "
                        "resumes it")
    p.add_argument("--no-plots", action="store_true", help="skip the PNG plots")
    p.set_defaults(func=_cmd_sweep)


def _cmd_sweep(args: argparse.Namespace) -> int:
    from lanekeep.sweep.run import FINISHED, ray_missing, run_local, run_ray
    from lanekeep.sweep.spec import check_world, load_sweep
    from lanekeep.sweep.store import SweepStore

    if args.workers is not None and args.workers < 1:
        raise ConfigError("", "--workers", f"must be >= 1, got {args.workers}")
    if args.ray is not None and (why := ray_missing()):
        raise ConfigError("", "--ray", why.removeprefix("--ray "))
    spec = load_sweep(args.file)
    check_world(spec)  # each value through the one validation path, before any worker
    out = Path(args.out) if args.out else Path("out/sweeps") / spec.name
    store = SweepStore(out, spec)
    cells = spec.cells()
    done = store.finished_ids()
    todo = [c for c in cells if c.cell_id not in done]
    by_id = {c.cell_id: c for c in cells}
    print(f"sweep {spec.name}: {len(cells)} cells ({len(cells) // len(spec.seeds)} parameter "
          f"combinations x {len(spec.seeds)} seeds); {len(cells) - len(todo)} already done, "
          f"{len(todo)} to run -> {out}", file=sys.stderr)
    failed: list[str] = []
    bar = _cell_bar(len(todo), spec.name)

    def on_result(result) -> None:
        store.add(by_id[result.cell_id], result)
        if result.status not in FINISHED:
            failed.append(f"{result.cell_id}: {result.status}: {result.error}")
        bar.update(1)

    start = time.perf_counter()
    try:
        with bar:
            if not todo:
                pass
            elif args.ray is not None:
                run_ray(todo, spec.source, spec.seconds, on_result, address=args.ray or None,
                        num_cpus=args.workers)
            else:
                run_local(todo, spec.source, spec.seconds, args.workers or 2, on_result)
    except KeyboardInterrupt:
        store.write()
        print(f"sweep interrupted: {len(store.finished_ids())} of {len(cells)} cells done, "
              f"kept in {out}; run the same command to resume", file=sys.stderr)
        return 130
    wall = time.perf_counter() - start
    results, summary = store.write()
    print(f"ran {len(todo)} cells in {wall:.1f} s; {results}, {summary}")
    if not args.no_plots:
        from lanekeep.sweep.plots import plot_sweep

        plots = plot_sweep(spec, store.rows(), out / "plots")
        print(f"{len(plots)} plots in {out / 'plots'}")
    for line in failed:
        print(f"FAILED {line}", file=sys.stderr)
    return 1 if failed else 0


def _cell_bar(total: int, label: str):
    """Cells done, elapsed and remaining time (tqdm; on a terminal only)."""
    from tqdm import tqdm

    return tqdm(total=total, desc=f"sweep {label}", unit="cell", file=sys.stderr,
                disable=not sys.stderr.isatty(), dynamic_ncols=True,
                bar_format="{desc}: {percentage:3.0f}%|{bar}| {n_fmt}/{total_fmt} cells "
                           "[{elapsed}<{remaining}]")
