"""`lanekeep falsify FILE [--budget N] [--workers N | --ray [ADDRESS]] [--out DIR] [--json F]
[--seed N] [--sampler tpe|random]`: search scenario parameters for the drive that fails.

FILE is a sweep file whose parameters may be ranges (lanekeep/sweep/falsify_spec.py); the
margin searched is the scenario's criteria as a number, negative when the drive fails
(lanekeep/sweep/falsify_objective.py). Optuna's sampler, seeded, asks candidates in batches;
they run on local workers or Ray through the sweep's runners, each written down as it finishes
(lanekeep/sweep/falsify_store.py), so the same command again resumes (a larger --budget goes
on). At the end, in --out: results.parquet, summary.json, worst_K.toml (scenario files that
`lanekeep run FILE --seed S` reproduces), minimal.toml (the worst failure with each parameter
moved back toward the base while it still fails), margin_vs_parameters.png.

Exit codes: 0 no failing drive found, 1 a failing drive found (or an episode raised),
2 bad input, 130 interrupted (the finished episodes are kept; run it again to resume).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from lanekeep.core.config_io import ConfigError

SEARCH_HELP = "tpe: Optuna's TPE (default); random: random search, the baseline"


def register(sub) -> None:
    p = sub.add_parser("falsify", help="search scenario parameters for failing drives "
                                       "(Optuna; local workers or Ray); resumable; failing "
                                       "cases as scenario files",
                       description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("file", help="falsify file (.toml): a sweep file whose parameters may be "
                                "ranges { low, high }, and an optional [objective]")
    p.add_argument("--budget", type=int, default=40,
                   help="episodes of the search (trials x seeds; default 40); a larger one "
                        "in the same --out goes on from where the last stopped")
    p.add_argument("--batch", type=int, default=4,
                   help="trials asked and run together (default 4); part of the search's "
                        "identity, unlike --workers, so the same seed gives the same "
                        "candidates on any number of workers")
    p.add_argument("--seed", type=int, default=0, help="the sampler's seed (default 0)")
    p.add_argument("--sampler", choices=("tpe", "random"), default="tpe", help=SEARCH_HELP)
    p.add_argument("--workers", type=int, default=None,
                   help="local worker processes (default 2); with a local --ray, its CPUs")
    p.add_argument("--ray", nargs="?", const="", default=None, metavar="ADDRESS",
                   help="run the episodes as Ray tasks: a local Ray without ADDRESS, else the "
                        "cluster's (e.g. HEAD:6379 or auto); needs lanekeep[ray]")
    p.add_argument("--out", default=None,
                   help="output folder (default out/falsify/NAME/SAMPLER-seedN); one holding "
                        "this search resumes it")
    p.add_argument("--json", default=None, help="also write the summary here")
    p.add_argument("--worst", type=int, default=3, metavar="K",
                   help="write the K worst failing cases as scenario files (default 3)")
    p.add_argument("--no-shrink", action="store_true",
                   help="skip the minimal failing case (its episodes come on top of --budget)")
    p.add_argument("--record", action="store_true",
                   help="rerun each written case with a rerun recording (recordings/*.rrd)")
    p.add_argument("--no-plots", action="store_true", help="skip the PNG plot")
    p.set_defaults(func=_cmd_falsify)


def _check_options(args: argparse.Namespace) -> None:
    checks = [("--budget", args.budget, 1), ("--batch", args.batch, 1), ("--seed", args.seed, 0),
              ("--worst", args.worst, 0)]
    if args.workers is not None:
        checks.append(("--workers", args.workers, 1))
    for option, value, least in checks:
        if value < least:
            raise ConfigError("", option, f"must be >= {least}, got {value}")
    for module in ("optuna", "tomli_w", "pyarrow"):
        try:
            __import__(module)
        except ImportError:
            raise ConfigError("", "falsify", f"needs {module}: pip install "
                                             f"'lanekeep[falsify]'") from None
    if args.ray is not None:
        from lanekeep.sweep.run import ray_missing

        if why := ray_missing():
            raise ConfigError("", "--ray", why.removeprefix("--ray "))


def _cmd_falsify(args: argparse.Namespace) -> int:
    from contextlib import nullcontext

    from lanekeep.sweep.falsify_search import Evaluator, run_search
    from lanekeep.sweep.falsify_spec import load_falsify
    from lanekeep.sweep.falsify_store import FalsifyStore
    from lanekeep.sweep.run import ray_session, run_local, run_ray
    from lanekeep.sweep.spec import check_world

    _check_options(args)
    spec = load_falsify(args.file)
    check_world(spec.sweep, spec.table)  # each end value through the one validation path
    seeds = len(spec.sweep.seeds)
    if args.budget < seeds:
        raise ConfigError("", "--budget", f"must be at least the spec's {seeds} seeds (one "
                                          f"trial drives every seed), got {args.budget}")
    out = Path(args.out) if args.out else (Path("out/falsify") / spec.name /
                                           f"{args.sampler}-seed{args.seed}")
    search = {"sampler": args.sampler, "seed": args.seed, "batch": args.batch}
    store = FalsifyStore(out, spec, search)
    n_trials = args.budget // seeds
    print(f"falsify {spec.name}: {args.sampler} (seed {args.seed}), {n_trials} trials x "
          f"{seeds} seeds, batches of {args.batch}, over "
          f"{'; '.join(d.describe() for d in spec.dimensions)} -> {out}", file=sys.stderr)

    if args.ray is not None:
        session = ray_session(args.ray or None, args.workers)

        def execute(cells, on_result):
            run_ray(cells, spec.source, None, on_result)
    else:
        session = nullcontext()

        def execute(cells, on_result):
            run_local(cells, spec.source, None, args.workers or 2, on_result)

    bar = _bar(n_trials * seeds, spec.name)
    best = [None]

    def on_episode(row: dict) -> None:
        m = row.get("margin")
        if m is not None and (best[0] is None or m < best[0]):
            best[0] = m
            bar.set_postfix_str(f"best margin {m:+.3f}", refresh=False)
        bar.update(1)

    evaluate = Evaluator(spec, store, execute, on_episode)
    try:
        with session, bar:
            trials = run_search(spec, evaluate, args.sampler, args.seed, n_trials * seeds,
                                args.batch)
            minimal = None
            failing = [t for t in trials if t.margin is not None and t.margin < 0]
            if failing and not args.no_shrink:
                from lanekeep.sweep.falsify_shrink import LEVELS, shrink

                bar.set_description_str(f"shrink {spec.name}")
                bar.total += sum(1 if d.kind == "choice" else len(LEVELS)
                                 for d in spec.dimensions)
                minimal = shrink(spec, evaluate, min(failing, key=lambda t: (t.margin,
                                                                            t.number)))
                bar.total = bar.n
    except KeyboardInterrupt:
        store.write()
        print(f"falsify interrupted: {len(store.rows())} episodes kept in {out}; run the "
              f"same command to resume", file=sys.stderr)
        return 130
    return _finish(args, spec, store, out, search, trials, minimal, evaluate.ran)


def _finish(args, spec, store, out: Path, search: dict, trials, minimal, ran) -> int:
    from lanekeep.report.json_io import write_json
    from lanekeep.sweep.falsify_output import (
        PLOT,
        plot_margins,
        summary,
        worst,
        write_case,
    )

    results = store.write()
    how = f"{search['sampler']}, seed {search['seed']}"
    cases = [write_case(spec, out / f"worst_{i}.toml", f"worst {i}", t.number, t.values,
                        t.seed, t.margin, t.binding, how)
             for i, t in enumerate(worst(trials, args.worst), 1)]
    small = None
    if minimal is not None:
        small = (write_case(spec, out / "minimal.toml", "minimal failing case", -1,
                            minimal.values, minimal.seed, minimal.margin, minimal.binding,
                            f"{how}, shrunk"), minimal)
    doc = summary(spec, {**search, "budget": args.budget}, trials, cases, small, ran)
    write_json(out / "summary.json", doc)
    if args.json:
        write_json(args.json, doc)
    if not args.no_plots:
        plot_margins(spec, store.rows(), doc["minimal"], out / PLOT)
    print(f"{doc['trials']} trials ({doc['episodes_search']} episodes; run now: "
          f"{ran['search']} search, {ran['shrink']} shrink); {results}")
    if doc["best"] is not None:
        b = doc["best"]
        print(f"lowest margin {b['margin']:+.4f} (trial {b['trial']}, seed {b['seed']}, "
              f"{b['binding'] or 'no criterion binding'}): {b['parameters']}")
    if doc["first_failure_after_episodes"] is None:
        print(f"no failing drive in {doc['episodes_search']} episodes")
    else:
        print(f"first failing drive after {doc['first_failure_after_episodes']} episode(s); "
              f"{doc['failing_trials']} failing trials")
    for case in cases + ([small[0]] if small else []):
        print(f"  {case.label}: margin {case.margin:+.4f} ({case.binding}): {case.command}")
    if small is not None:
        needed = ", ".join(small[1].needed) or "none"
        print(f"  minimal case needs: {needed} ({small[1].episodes} shrink episodes)")
    if args.record:
        _record(cases + ([small[0]] if small else []), out / "recordings")
    if doc["episodes_raised"]:
        print(f"{doc['episodes_raised']} trials had an episode that raised (status failed; "
              f"see {results})", file=sys.stderr)
    return 1 if doc["failing_trials"] or doc["episodes_raised"] else 0


def _record(cases, folder: Path) -> None:
    """A rerun recording of each case, driven as `lanekeep run` drives it."""
    from lanekeep.loop.runner import run_episode

    folder.mkdir(parents=True, exist_ok=True)
    for case in cases:
        path = folder / f"{case.path.stem}.rrd"
        report = run_episode(str(case.path), case.seed, record_path=str(path))
        print(f"  recorded {path} ({'passed' if report.passed else 'failed'})")


def _bar(total: int, label: str):
    """Episodes done and the lowest margin so far (tqdm; on a terminal only)."""
    from tqdm import tqdm

    return tqdm(total=total, desc=f"falsify {label}", unit="episode", file=sys.stderr,
                disable=not sys.stderr.isatty(), dynamic_ncols=True,
                bar_format="{desc}: {percentage:3.0f}%|{bar}| {n_fmt}/{total_fmt} episodes "
                           "[{elapsed}<{remaining}{postfix}]")
