"""Two `bench --json` runs paired seed by seed: is B better than A?

A user changes a detector, an estimator, a controller or a setting and runs the bench again on
the same scenarios and seeds. Both runs drove the same seeded episodes, so each (scenario,
seed) is a pair and what the seed does to both (the drive, the start, the noise) cancels in
the difference. For each metric and label: the mean of the per-seed differences B - A, its
95% paired t interval and the verdict for B (lanekeep/scoring/statistics.py): "better" or
"worse" only when the interval excludes 0, else "indistinguishable".

The "all" row pools every (label, seed) pair of every label into one paired interval: a label
with larger errors (a hard scenario, a model-only loop) weighs more there, so read it beside
the per-label rows and the verdict counts, which count each label once (never raw wins).

a_mean and b_mean are the means over the n pairs where both values are finite (a source with
no estimate gives NaN / null), so that diff = b_mean - a_mean.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from typing import Any

from lanekeep.core.reproducibility import kernel_differences
from lanekeep.report.json_io import SCHEMA_VERSION, lanekeep_version
from lanekeep.report.seed_summary import EPISODE_KEYS, HIGHER_IS_BETTER, SOURCE_KEYS
from lanekeep.scoring import statistics as stats

WIDTH = 120  # the table keeps within this many columns
NOT_BENCH = f"not a bench --json document (schema_version {SCHEMA_VERSION})"


class IncomparableRuns(ValueError):
    """The two runs cannot be paired (other labels or seeds), a file is no bench document, or a
    metric names a source a run lacks; the message is one line saying what differs."""


@dataclass(frozen=True)
class Metric:
    """One compared number of an episode: `field` of source `source`, or of the episode itself
    when `source` is None."""

    source: str | None
    field: str

    @property
    def key(self) -> str:
        """"fused.rmse_cm" for a source's field, "car_rms_cm" for an episode's."""
        return self.field if self.source is None else f"{self.source}.{self.field}"

    @property
    def lower_is_better(self) -> bool:
        return self.field not in HIGHER_IS_BETTER


def source_metrics(source: str) -> tuple[Metric, ...]:
    """A source's compared fields: the errors (lower better) and its valid share (higher)."""
    return tuple(Metric(source, f) for f in ("rmse_cm", "max_cm", "ade_cm", "fde_cm",
                                             "valid_share"))


DEFAULT_METRICS = (*source_metrics("fused"), Metric(None, "car_rms_cm"),
                   Metric(None, "car_max_cm"), Metric(None, "lane_departures"))
# The table's columns (the --json output holds every metric); other sources add their RMSE.
TABLE_KEYS = ("fused.rmse_cm", "car_rms_cm", "car_max_cm", "lane_departures")


def parse_metric(key: str) -> Metric:
    """A Metric from its key ("fused.rmse_cm", "hough:track.drift_cm", "car_rms_cm");
    ValueError naming the keys allowed otherwise."""
    if key in EPISODE_KEYS:
        return Metric(None, key)
    source, _, field = key.rpartition(".")
    if source and field in SOURCE_KEYS:
        return Metric(source, field)
    raise ValueError(f"unknown metric {key!r}: use SOURCE.FIELD with FIELD one of "
                     f"{', '.join(SOURCE_KEYS)} (e.g. fused.rmse_cm), or one of "
                     f"{', '.join(EPISODE_KEYS)}")


def metric_set(keys: Sequence[str] | None = None, sources: Sequence[str] = ()
               ) -> tuple[Metric, ...]:
    """`keys` (default DEFAULT_METRICS) and every source's metrics, each once, in order."""
    chosen = [parse_metric(k) for k in keys] if keys else list(DEFAULT_METRICS)
    for source in sources:
        chosen += source_metrics(source)
    return tuple(dict.fromkeys(chosen))


@dataclass(frozen=True)
class Run:
    """One bench --json file's documents, checked to be bench documents, named for messages."""

    name: str
    docs: dict[str, dict]

    def episodes(self, label: str) -> dict[int, dict]:
        """The label's episode documents by seed."""
        return {e["seed"]: e for e in self.docs[label]["episodes"]}

    def first(self) -> dict:
        return next(iter(self.docs.values()))


def check_bench(document: Any, name: str) -> Run:
    """`document` as a Run if it is a bench --json document (schema_version 2), else
    IncomparableRuns saying why (a `run --json` report, an old bench file, anything else)."""
    if not isinstance(document, dict) or not document:
        raise IncomparableRuns(f"{name}: {NOT_BENCH}: expected an object of labels")
    if "schema_version" in document:  # one document, not a map of labels
        what = "an episode's report (`run --json`)" if "sources" in document else "one document"
        raise IncomparableRuns(f"{name}: {NOT_BENCH}: it is {what}, not one document per label")
    for label, doc in document.items():
        if not (isinstance(doc, dict) and isinstance(doc.get("episodes"), list)
                and isinstance(doc.get("seeds"), list)):
            raise IncomparableRuns(f"{name}: {NOT_BENCH}: {label!r} has no seeds and episodes "
                                   "(a `run --json` report or a schema_version 1 bench file?)")
        if doc.get("schema_version") != SCHEMA_VERSION:
            raise IncomparableRuns(f"{name}: {NOT_BENCH}: {label!r} has schema_version "
                                   f"{doc.get('schema_version')}")
        seeds = [e.get("seed") if isinstance(e, dict) else None for e in doc["episodes"]]
        if sorted(seeds, key=str) != sorted(doc["seeds"], key=str):
            raise IncomparableRuns(f"{name}: {NOT_BENCH}: {label!r} lists seeds {doc['seeds']} "
                                   f"but its episodes have {seeds}")
    return Run(name, document)


def _seeds_text(seeds: Sequence) -> str:
    seeds = sorted(seeds)
    if len(seeds) > 2 and seeds == list(range(seeds[0], seeds[-1] + 1)):
        return f"{seeds[0]}..{seeds[-1]}"
    return ", ".join(str(s) for s in seeds) if len(seeds) <= 8 else f"{seeds[:8]}..."


def check_pairing(a: Run, b: Run) -> list[str]:
    """IncomparableRuns unless both ran the same labels on the same seeds; the labels in A's
    order."""
    only_a = [k for k in a.docs if k not in b.docs]
    only_b = [k for k in b.docs if k not in a.docs]
    if only_a or only_b:
        parts = [f"only in {r.name}: {', '.join(ks)}" for r, ks in ((a, only_a), (b, only_b))
                 if ks]
        raise IncomparableRuns(f"the runs have different labels ({'; '.join(parts)})")
    for label in a.docs:
        sa, sb = a.docs[label]["seeds"], b.docs[label]["seeds"]
        if sorted(sa) != sorted(sb):
            raise IncomparableRuns(f"{label}: the runs have different seeds ({a.name}: "
                                   f"{_seeds_text(sa)}; {b.name}: {_seeds_text(sb)})")
    return list(a.docs)


def _number(value: Any, where: str) -> float:
    """A JSON number as float (null: NaN, no estimate); IncomparableRuns for anything else."""
    if value is None:
        return math.nan
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise IncomparableRuns(f"{where}: {NOT_BENCH}: expected a number, got {value!r}")
    return float(value)


def metric_value(run: Run, label: str, episode: dict, metric: Metric) -> float:
    """`metric` of one episode document; IncomparableRuns naming a source or key it lacks."""
    where = f"{run.name}: {label} seed {episode['seed']}"
    if metric.source is None:
        if metric.field not in episode:
            raise IncomparableRuns(f"{where}: {NOT_BENCH}: no {metric.field!r}")
        return _number(episode[metric.field], where)
    sources = episode.get("sources") or {}
    if metric.source not in sources:
        raise IncomparableRuns(f"source {metric.source!r} is not in {run.name} ({label} seed "
                               f"{episode['seed']} has {', '.join(sources) or 'none'})")
    return _number(sources[metric.source].get(metric.field), f"{where}: {metric.source}")


def _pairs(a: Run, b: Run, label: str, metric: Metric) -> list[tuple[float, float]]:
    """(A, B) of `metric` for each seed of `label`, in seed order."""
    ea, eb = a.episodes(label), b.episodes(label)
    return [(metric_value(a, label, ea[s], metric), metric_value(b, label, eb[s], metric))
            for s in sorted(ea)]


def compare_pairs(pairs: Sequence[tuple[float, float]], metric: Metric) -> dict[str, Any]:
    """{a_mean, b_mean, diff, ci95, verdict, n} of B - A over `pairs` (verdict for B)."""
    both = [(x, y) for x, y in pairs if math.isfinite(x) and math.isfinite(y)]
    a_values, b_values = [x for x, _ in both], [y for _, y in both]
    p = stats.paired(b_values, a_values, metric.lower_is_better)
    return {"a_mean": _mean(a_values), "b_mean": _mean(b_values), "diff": p.diff,
            "ci95": list(p.ci95), "verdict": p.verdict, "n": p.n}


def _mean(values: Sequence[float]) -> float:
    return sum(values) / len(values) if values else math.nan


def _notes(a: Run, b: Run, labels: Sequence[str]) -> list[str]:
    """What a reader should know beside the numbers: scenario files or versions that differ,
    episodes that did not complete, too few seeds for any verdict."""
    notes = []
    for label in labels:
        ha, hb = a.docs[label].get("scenario_sha256"), b.docs[label].get("scenario_sha256")
        if ha != hb:
            notes.append(f"scenario file differs: {label} ({a.name} sha256 {str(ha)[:12]}, "
                         f"{b.name} {str(hb)[:12]})")
    va, vb = a.first().get("lanekeep_version"), b.first().get("lanekeep_version")
    if va != vb:
        notes.append(f"lanekeep version differs: {a.name} {va}, {b.name} {vb}")
    kernels = kernel_differences(a.first().get("reproducibility"),
                                 b.first().get("reproducibility"))
    if kernels:
        notes.append(f"kernel settings differ ({', '.join(kernels)}): the two runs would not "
                     "agree to the bit even without a change; a verdict still holds, an exact "
                     "tie does not (docs/reproducibility.md#across-machines)")
    for run in (a, b):
        for label in labels:
            for seed, e in sorted(run.episodes(label).items()):
                if e.get("status", "completed") != "completed":
                    notes.append(f"{run.name}: {label} seed {seed} did not complete "
                                 f"({e.get('status')}): its metrics cover part of the drive")
    if all(len(a.docs[label]["seeds"]) < 2 for label in labels):
        notes.append("one seed per label: no interval, every per-label verdict "
                     "indistinguishable (run bench with --seeds N)")
    return notes


def run_settings(doc: dict) -> dict[str, Any]:
    """A run's command-line changes as its first document records them, with its mode."""
    return {**(doc.get("overrides") or {}), "mode": doc.get("mode")}


def compare_runs(a: dict, b: dict, metrics: Iterable[Metric | str] = DEFAULT_METRICS,
                 a_name: str = "A", b_name: str = "B") -> dict[str, Any]:
    """B - A per label and metric, paired over seeds, and pooled over every pair ("all").

    `a`, `b`: two bench --json documents (label -> document); `a_name`, `b_name` name them in
    messages and in the result. IncomparableRuns if they cannot be paired. Returns {a, b,
    a_overrides, b_overrides, seeds, better_when, labels, all, counts, notes} (KEYS_HELP)."""
    ra, rb = check_bench(a, a_name), check_bench(b, b_name)
    labels = check_pairing(ra, rb)
    chosen = tuple(m if isinstance(m, Metric) else parse_metric(m) for m in metrics)
    per_label: dict[str, dict[str, Any]] = {label: {} for label in labels}
    pooled: dict[str, Any] = {}
    for metric in chosen:
        every = []
        for label in labels:
            pairs = _pairs(ra, rb, label, metric)
            per_label[label][metric.key] = compare_pairs(pairs, metric)
            every += pairs
        pooled[metric.key] = compare_pairs(every, metric)
    counts = {m.key: stats.count_verdicts([per_label[label][m.key]["verdict"]
                                           for label in labels]) for m in chosen}
    return {
        "a": a_name, "b": b_name,
        "a_overrides": run_settings(ra.first()), "b_overrides": run_settings(rb.first()),
        "seeds": {label: sorted(ra.docs[label]["seeds"]) for label in labels},
        "better_when": {m.key: "lower" if m.lower_is_better else "higher" for m in chosen},
        "labels": per_label, "all": pooled, "counts": counts, "notes": _notes(ra, rb, labels),
    }


def compare_document(result: dict) -> dict:
    """The --json document: `result` led by schema_version and lanekeep_version."""
    return {"schema_version": SCHEMA_VERSION, "lanekeep_version": lanekeep_version(), **result}


KEYS_HELP = """\
compare --json: one document (strict JSON: NaN is null):
  schema_version, lanekeep_version     as every lanekeep document
  a, b                                 the two files (B is judged against A)
  a_overrides, b_overrides             each run's command-line changes (front_detectors,
                                       reference_detector, controller, settings, weights)
                                       and its mode, from its first document
  seeds.LABEL                          the seeds paired
  better_when.METRIC                   "lower" or "higher" (valid_share)
  labels.LABEL.METRIC                  {a_mean, b_mean, diff, ci95, verdict, n}: diff = mean of
                                       B - A per seed = b_mean - a_mean, means over the n pairs
                                       where both are finite; ci95 its paired 95% t interval
                                       [lo, hi]; verdict for B: better / worse /
                                       indistinguishable
  all.METRIC                           the same over every (label, seed) pair pooled (labels
                                       with larger errors weigh more)
  counts.METRIC                        {better, worse, indistinguishable}: verdicts over labels
  notes                                scenario files or versions that differ, episodes that
                                       did not complete
METRIC: SOURCE.FIELD (fused.rmse_cm, hough:track.max_cm, ...) or an episode's car_rms_cm,
car_max_cm, lane_departures, ...
"""


# --- the terminal table ---------------------------------------------------------------------

def _digits(key: str) -> int:
    """Decimals shown: the car's errors in mm are noise, a share needs three."""
    if key.endswith("valid_share"):
        return 3
    return 1 if key.startswith("car_") else 2


def _signed(x: float, digits: int) -> str:
    return f"{x:+.{digits}f}"


def cell_text(entry: dict, key: str) -> str:
    """"+0.12 [-0.40, +0.64] i": B - A, its interval, the verdict's letter; "-" for no pair."""
    diff, (lo, hi) = entry["diff"], entry["ci95"]
    if diff is None or not math.isfinite(diff):
        return "-"
    d = _digits(key)
    letter = entry["verdict"][0]
    if lo is None or hi is None or not (math.isfinite(lo) and math.isfinite(hi)):
        return f"{_signed(diff, d)} {letter}"
    return f"{_signed(diff, d)} [{_signed(lo, d)}, {_signed(hi, d)}] {letter}"


def table_keys(result: dict) -> list[str]:
    """The table's columns: TABLE_KEYS present, each other source's RMSE; else every metric."""
    keys = list(result["better_when"])
    shown = [k for k in TABLE_KEYS if k in keys]
    shown += [k for k in keys if k.endswith(".rmse_cm") and k not in shown]
    return shown or keys


def _differences(result: dict) -> str:
    """What the runs' command lines changed, e.g. "controller: (scenario file's) -> stanley"."""
    sa, sb = result["a_overrides"], result["b_overrides"]

    def show(v: Any) -> str:
        if v is None or v == []:
            return "(scenario file's)"
        if isinstance(v, list):
            return " ".join(f"{x[0]}={x[1]}" if isinstance(x, list) and len(x) == 2 else str(x)
                            for x in v)
        return str(v)

    changed = [f"{k}: {show(sa.get(k))} -> {show(sb.get(k))}"
               for k in dict.fromkeys([*sa, *sb]) if sa.get(k) != sb.get(k)]
    if not changed:
        return "same command-line overrides and mode (the change is elsewhere: code, files)"
    return "; ".join(changed)


def _block(result: dict, keys: Sequence[str]) -> list[str]:
    """Rows = labels and "all", columns = `keys`."""
    rows = [(label, result["labels"][label]) for label in result["labels"]]
    rows.append(("all (pooled)", result["all"]))
    label_w = max(len(r[0]) for r in rows) + 2
    cells = [[cell_text(entry[k], k) for k in keys] for _, entry in rows]
    widths = [max(len(k), *(len(c[i]) for c in cells)) + 2 for i, k in enumerate(keys)]
    header = f"{'label':<{label_w}}" + "".join(f"{k:<{w}}" for k, w in zip(keys, widths,
                                                                             strict=True))
    lines = [header.rstrip(), "-" * len(header.rstrip())]
    for (label, _), row in zip(rows, cells, strict=True):
        lines.append((f"{label:<{label_w}}" + "".join(
            f"{c:<{w}}" for c, w in zip(row, widths, strict=True))).rstrip())
    return lines


def _column_groups(result: dict, keys: Sequence[str]) -> list[list[str]]:
    """`keys` split into groups whose block fits WIDTH columns (one group as a rule)."""
    groups: list[list[str]] = [[]]
    for key in keys:
        if groups[-1] and max(len(x) for x in _block(result, [*groups[-1], key])) > WIDTH:
            groups.append([])
        groups[-1].append(key)
    return groups


def _wrapped(head: str, items: Sequence[str]) -> list[str]:
    """`head` and `items` two spaces apart, wrapped at WIDTH, continuation lines indented."""
    lines, line = [], head
    for item in items:
        if len(line) + 2 + len(item) > WIDTH:
            lines.append(line)
            line = ""
        line += "  " + item
    return [*lines, line]


def compare_table(result: dict) -> str:
    """The comparison on one screen: what A and B are, B - A [95% CI] and verdict letter per
    label for the key metrics, the verdict counts of every metric, the notes."""
    seeds = {len(s) for s in result["seeds"].values()}
    n_text = "/".join(str(n) for n in sorted(seeds))
    lines = [f"A = {result['a']}", f"B = {result['b']}",
             f"differs: {_differences(result)}",
             f"B - A: mean of the per-seed differences over {n_text} seeds [paired 95% t "
             "interval] and the verdict for B,",
             "b / w / i = better / worse / indistinguishable; better = B lower (higher for "
             "valid_share)", ""]
    for group in _column_groups(result, table_keys(result)):
        lines += [*_block(result, group), ""]
    counts = [f"{k} {c['better']}b {c['worse']}w {c['indistinguishable']}i"
              for k, c in result["counts"].items()]
    lines += _wrapped(f"verdicts for B over {len(result['labels'])} labels (b / w / i):", counts)
    lines += [f"note: {n}" for n in result["notes"]]
    return "\n".join(lines)
