"""Two `bench --json` runs paired seed by seed: is B better than A, by a margin that matters?

A user changes a detector, an estimator, a controller or a setting and runs the bench again on
the same scenarios and seeds. Both runs drove the same seeded episodes, so each (scenario,
seed) is a pair and what the seed does to both (the drive, the start, the noise) cancels in
the difference. For each metric and label: B - A per seed (a log ratio for errors, given back
in cm), its paired 95% interval, the metric's margin of practical relevance and the verdict for
B (lanekeep/scoring/statistics.py): better / worse only beyond the margin, equivalent within
it, non-inferior / non-superior on one side, inconclusive (with the smallest difference this
n detects), too few below three seeds. Departures: McNemar's exact test per seed.

The "all" row is stratified: each label's own mean difference and standard error, averaged
with equal weight (each scenario counts once), Welch-Satterthwaite degrees of freedom, and a
sign test over the labels; it never pools the raw pairs (one noisy scenario would swamp the
rest). The verdict counts come with Holm-adjusted counts of better / worse within each metric
and the number chance alone would give.

a_mean and b_mean are the means over the n pairs where both values are finite (a source with
no estimate gives NaN / null); `dropped` counts the pairs left out, and a note names them.

The safety metrics (SAFETY_METRICS: collisions, hard_braking_events, min_ttc_s, min_gap_m) are
compared when asked for by name. Files written before them lack the keys: such a metric is
left out of the comparison with a note, never an error. An episode that never closed on a
vehicle ahead has no finite min_ttc_s (null) and its pair is dropped like a missing estimate.
"""

from __future__ import annotations

import math
import textwrap
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from typing import Any

from lanekeep.core.reproducibility import kernel_differences
from lanekeep.report.json_io import SCHEMA_VERSION, lanekeep_version
from lanekeep.report.seed_summary import EPISODE_KEYS, HIGHER_IS_BETTER, SOURCE_KEYS
from lanekeep.scoring import statistics as stats
from lanekeep.scoring.metrics import SAFETY_METRICS, drive_failed

WIDTH = 120  # the table keeps within this many columns
# An episode's "failed" (scoring.metrics.drive_failed): derived from its lane_departures and
# status, so that documents written before it was named compare on it too.
FAILED = "failed"
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
                   Metric(None, "car_max_cm"), Metric(None, "lane_departures"),
                   Metric(None, FAILED))
# The table's columns (the --json output holds every metric); other sources add their RMSE.
TABLE_KEYS = ("fused.rmse_cm", "car_rms_cm", "car_max_cm", "lane_departures", FAILED)


def parse_metric(key: str) -> Metric:
    """A Metric from its key ("fused.rmse_cm", "hough:track.drift_cm", "car_rms_cm");
    ValueError naming the keys allowed otherwise."""
    if key in EPISODE_KEYS or key in SAFETY_METRICS or key == FAILED:
        return Metric(None, key)
    source, _, field = key.rpartition(".")
    if source and field in SOURCE_KEYS:
        return Metric(source, field)
    raise ValueError(f"unknown metric {key!r}: use SOURCE.FIELD with FIELD one of "
                     f"{', '.join(SOURCE_KEYS)} (e.g. fused.rmse_cm), or one of "
                     f"{', '.join((*EPISODE_KEYS, FAILED, *SAFETY_METRICS))}")


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
    if metric.source is None and metric.field == FAILED:
        departures = metric_value(run, label, episode, Metric(None, "lane_departures"))
        return float(drive_failed(int(departures), str(episode.get("status", "completed"))))
    if metric.source is None:
        if metric.field not in episode:
            raise IncomparableRuns(f"{where}: {NOT_BENCH}: no {metric.field!r}")
        return _number(episode[metric.field], where)
    sources = episode.get("sources") or {}
    if metric.source not in sources:
        raise IncomparableRuns(f"source {metric.source!r} is not in {run.name} ({label} seed "
                               f"{episode['seed']} has {', '.join(sources) or 'none'})")
    return _number(sources[metric.source].get(metric.field), f"{where}: {metric.source}")


def carries(run: Run, labels: Sequence[str], field: str) -> bool:
    """Whether every episode of `labels` in `run` has the episode key `field`."""
    return all(field in e for label in labels for e in run.episodes(label).values())


def absent_metrics(a: Run, b: Run, labels: Sequence[str], metrics: Sequence[Metric]
                   ) -> tuple[list[Metric], list[str]]:
    """The safety metrics among `metrics` that a run's episodes lack (written before them),
    and a note for each: they are left out of the comparison rather than failing it."""
    absent, notes = [], []
    for m in metrics:
        if m.source is not None or m.field not in SAFETY_METRICS:
            continue
        lacking = [r.name for r in (a, b) if not carries(r, labels, m.field)]
        if lacking:
            absent.append(m)
            notes.append(f"{m.key} is not in {' and '.join(lacking)} (written before lanekeep "
                         "reported it): not compared")
    return absent, notes


def _pairs(a: Run, b: Run, label: str, metric: Metric) -> list[tuple[float, float]]:
    """(A, B) of `metric` for each seed of `label`, in seed order."""
    ea, eb = a.episodes(label), b.episodes(label)
    return [(metric_value(a, label, ea[s], metric), metric_value(b, label, eb[s], metric))
            for s in sorted(ea)]


def parse_margins(texts: Sequence[str]) -> dict[str, stats.Margin]:
    """`--margin [LABEL:]METRIC=ABS[,REL%]` values as {"[LABEL:]METRIC": Margin}; ValueError
    with the text that is wrong."""
    out = {}
    for text in texts:
        key, sep, value = text.partition("=")
        metric = key.rpartition(":")[2]
        try:
            if not sep or not key:
                raise ValueError
            parse_metric(metric)
            parts = [p.strip() for p in value.split(",")]
            absolute = float(parts[0])
            relative = float(parts[1].rstrip("%")) / 100.0 if len(parts) > 1 else 0.0
            if len(parts) > 2 or not (absolute >= 0 and relative >= 0):  # NaN too
                raise ValueError
        except ValueError:
            raise ValueError(f"--margin {text!r}: expected [LABEL:]METRIC=ABS[,REL%] with a "
                             "known metric, e.g. fused.rmse_cm=0.2,5% or "
                             "occlusion:car_max_cm=1") from None
        out[key] = stats.Margin(absolute, relative)
    return out


def margin_of(metric: Metric, label: str | None,
              margins: dict[str, stats.Margin] | None) -> stats.Margin:
    """The margin in force: the label's own override, the metric's override, the declared."""
    margins = margins or {}
    if label is not None and f"{label}:{metric.key}" in margins:
        return margins[f"{label}:{metric.key}"]
    return margins.get(metric.key, stats.margin_for(metric.field))


def compare_pairs(pairs: Sequence[tuple[float, float]], metric: Metric,
                  margin: stats.Margin | None = None) -> dict[str, Any]:
    """{a_mean, b_mean, diff, ci95, verdict, n, margin, p_worse, p_better, detectable,
    dropped, ratio, ratio_ci95} of B - A over `pairs` (verdict for B)."""
    both = [(x, y) for x, y in pairs if math.isfinite(x) and math.isfinite(y)]
    a_values, b_values = [x for x, _ in both], [y for _, y in both]
    if stats.is_exact(metric.field):
        p = stats.paired_events([y > 0 for y in b_values], [x > 0 for x in a_values])
    else:
        p = stats.paired(b_values, a_values, metric.lower_is_better,
                         margin=margin or stats.margin_for(metric.field),
                         log_scale=stats.is_log_scale(metric.field))
    out = {"a_mean": _mean(a_values), "b_mean": _mean(b_values), **p.as_dict("")}
    out["dropped"] = len(pairs) - len(both)
    return out


def pool_labels(per_label_pairs: Sequence[Sequence[tuple[float, float]]], metric: Metric,
                margin: stats.Margin | None = None) -> dict[str, Any]:
    """The stratified "all" row of one metric over labels (statistics.pooled); departures:
    McNemar over every (label, seed) pair (exact; the pairs are the units)."""
    if stats.is_exact(metric.field):
        every = [pair for pairs in per_label_pairs for pair in pairs
                 if math.isfinite(pair[0]) and math.isfinite(pair[1])]
        p = stats.paired_events([y > 0 for _, y in every], [x > 0 for x, _ in every])
        return {"diff": p.diff, "ci95": list(p.ci95), "verdict": p.verdict, "scale": "rate",
                "labels": len(per_label_pairs), "n": p.n, "p_worse": p.p_worse,
                "p_better": p.p_better}
    pool = stats.pooled([([y for _, y in pairs], [x for x, _ in pairs])
                         for pairs in per_label_pairs], metric.lower_is_better,
                        metric.field, margin)
    return {"diff": pool.diff, "ci95": list(pool.ci95), "verdict": pool.verdict,
            "scale": "ratio" if pool.log_scale else "difference", "labels": pool.labels,
            "df": pool.df, "margin": pool.margin, "sign_test_p": pool.sign_p,
            "labels_up": pool.up, "labels_down": pool.down}


def claim_counts(entries: Sequence[dict]) -> dict[str, Any]:
    """The verdicts of one metric over labels, with Holm's adjustment of the better / worse
    claims (each label's one-sided p-values) and what chance alone gives."""
    counts: dict[str, Any] = stats.count_verdicts([e["verdict"] for e in entries])
    for claim, key in (("better", "p_better"), ("worse", "p_worse")):
        adjusted = stats.holm([_finite(e.get(key)) for e in entries])
        counts[f"{claim}_holm"] = sum(1 for p, e in zip(adjusted, entries, strict=True)
                                      if p < stats.ALPHA_ONE_SIDED and e["verdict"] == claim)
    counts["expected_by_chance"] = stats.expected_by_chance(len(entries))
    return counts


def _finite(value: Any) -> float:
    return float(value) if isinstance(value, (int, float)) and math.isfinite(value) else math.nan


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
                fused = (e.get("sources") or {}).get("fused") or {}
                if fused.get("rmse_cm") is None:
                    notes.append(f"{run.name}: {label} seed {seed} has no fused estimate: "
                                 "its pairs are dropped from the error metrics (counted in "
                                 "`dropped`)")
                if e.get("status", "completed") != "completed":
                    notes.append(f"{run.name}: {label} seed {seed} did not complete "
                                 f"({e.get('status')}): its metrics cover part of the drive")
    if all(len(a.docs[label]["seeds"]) < stats.MIN_PAIRS for label in labels):
        notes.append(f"fewer than {stats.MIN_PAIRS} seeds per label: no verdict (run bench "
                     "with --seeds N)")
    return notes


def run_settings(doc: dict) -> dict[str, Any]:
    """A run's command-line changes as its first document records them, with its mode."""
    return {**(doc.get("overrides") or {}), "mode": doc.get("mode")}


def compare_runs(a: dict, b: dict, metrics: Iterable[Metric | str] = DEFAULT_METRICS,
                 a_name: str = "A", b_name: str = "B",
                 margins: dict[str, stats.Margin] | None = None) -> dict[str, Any]:
    """B - A per label and metric, paired over seeds, and stratified over labels ("all").

    `a`, `b`: two bench --json documents (label -> document); `a_name`, `b_name` name them in
    messages and in the result; `margins` overrides declared margins ("METRIC" or
    "LABEL:METRIC", see parse_margins). IncomparableRuns if they cannot be paired. Returns {a,
    b, a_overrides, b_overrides, seeds, better_when, margins, labels, all, counts, notes}
    (KEYS_HELP)."""
    ra, rb = check_bench(a, a_name), check_bench(b, b_name)
    labels = check_pairing(ra, rb)
    chosen = tuple(m if isinstance(m, Metric) else parse_metric(m) for m in metrics)
    absent, absent_notes = absent_metrics(ra, rb, labels, chosen)
    chosen = tuple(m for m in chosen if m not in absent)
    per_label: dict[str, dict[str, Any]] = {label: {} for label in labels}
    pooled: dict[str, Any] = {}
    counts: dict[str, Any] = {}
    for metric in chosen:
        every = []
        for label in labels:
            pairs = _pairs(ra, rb, label, metric)
            per_label[label][metric.key] = compare_pairs(pairs, metric,
                                                         margin_of(metric, label, margins))
            every.append(pairs)
        pooled[metric.key] = pool_labels(every, metric, margin_of(metric, None, margins))
        counts[metric.key] = claim_counts([per_label[label][metric.key] for label in labels])
    return {
        "a": a_name, "b": b_name,
        "a_overrides": run_settings(ra.first()), "b_overrides": run_settings(rb.first()),
        "seeds": {label: sorted(ra.docs[label]["seeds"]) for label in labels},
        "better_when": {m.key: "lower" if m.lower_is_better else "higher" for m in chosen},
        "margins": {m.key: margin_of(m, None, margins).text() for m in chosen},
        "labels": per_label, "all": pooled, "counts": counts,
        "notes": absent_notes + _notes(ra, rb, labels),
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
  margins.METRIC                       the margin of practical relevance in force, e.g.
                                       "max(0.1, 5%)" (cm, or a share of A's size)
  labels.LABEL.METRIC                  {a_mean, b_mean, diff, ci95, verdict, n, margin,
                                       p_worse, p_better, detectable, dropped, ratio,
                                       ratio_ci95}: diff = B - A per seed averaged (on the log
                                       scale for errors: A's geometric mean x (ratio - 1), cm),
                                       ci95 its paired 95% interval; margin in cm; verdict for
                                       B: better / worse (beyond the margin), equivalent,
                                       non-inferior, non-superior, inconclusive, too few (< 3
                                       seeds); p_worse / p_better the one-sided p-values
                                       against the margin; detectable the smallest difference
                                       this n finds (80% power); dropped the pairs left out
                                       (no value); departures and failed: McNemar's exact
                                       test, diff the difference of the rates
  all.METRIC                           stratified over labels (each counts once): {diff, ci95,
                                       verdict, scale ("ratio" for errors: B / A, geometric
                                       mean over labels; "difference"; "rate"), labels, df,
                                       margin, sign_test_p, labels_up, labels_down}
  counts.METRIC                        verdicts over labels, better_holm / worse_holm (those
                                       that survive Holm's adjustment within the metric) and
                                       expected_by_chance (of each claim, at most)
  notes                                scenario files or versions that differ, episodes that
                                       did not complete or had no estimate, safety metrics a
                                       file lacks (not compared)
METRIC: SOURCE.FIELD (fused.rmse_cm, hough:track.max_cm, ...) or an episode's car_rms_cm,
car_max_cm, lane_departures, ...; failed (1 when the drive departed or ended off the road, in a
collision or in unstable physics: a collision can end a drive before it departs; exact, like
the departures); the safety metrics on request: collisions (exact, like the
departures), hard_braking_events, min_ttc_s and min_gap_m (higher better; an episode that
never closed on a vehicle ahead has no min_ttc_s)
"""


# --- the terminal table ---------------------------------------------------------------------

def _digits(key: str) -> int:
    """Decimals shown: the car's errors in mm are noise, a share needs three."""
    if key.endswith("valid_share"):
        return 3
    return 1 if key.startswith(("car_", "min_")) else 2


def _signed(x: float, digits: int) -> str:
    return f"{x:+.{digits}f}"


def cell_text(entry: dict, key: str) -> str:
    """"+0.12 [-0.40, +0.64] i": B - A, its interval, the verdict's letter; "-" for no pair.
    A stratified row on the ratio scale reads "+3.1% [-1.0, +7.3] e"."""
    diff, (lo, hi) = entry["diff"], entry["ci95"]
    if diff is None or not math.isfinite(diff):
        return "-"
    letter = stats.LETTERS.get(entry["verdict"], "?")
    if entry.get("scale") == "ratio":
        def pct(x: float | None) -> str:
            return "?" if x is None or not math.isfinite(x) else f"{100 * (x - 1):+.1f}"
        return f"{pct(diff)}% [{pct(lo)}, {pct(hi)}] {letter}"
    d = _digits(key)
    if lo is None or hi is None or not (math.isfinite(lo) and math.isfinite(hi)):
        return f"{_signed(diff, d)} {letter}"
    return f"{_signed(diff, d)} [{_signed(lo, d)}, {_signed(hi, d)}] {letter}"


def table_keys(result: dict) -> list[str]:
    """The table's columns: TABLE_KEYS present, each other source's RMSE, the safety metrics
    asked for; else every metric."""
    keys = list(result["better_when"])
    shown = [k for k in TABLE_KEYS if k in keys]
    shown += [k for k in keys if k.endswith(".rmse_cm") and k not in shown]
    shown += [k for k in keys if k in SAFETY_METRICS]
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
    rows.append(("all (stratified)", result["all"]))
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
    higher = ", ".join(["valid_share", *(k for k, way in result["better_when"].items()
                                         if way == "higher" and k in SAFETY_METRICS)])
    lines = [f"A = {result['a']}", f"B = {result['b']}",
             f"differs: {_differences(result)}",
             *textwrap.wrap(f"B - A: mean of the per-seed differences over {n_text} seeds "
                            "[paired 95% interval; errors on the log scale] and the verdict "
                            "for B against each metric's margin:", WIDTH),
             *_wrapped("", [f"{k} {v}" for k, v in result.get("margins", {}).items()]),
             *textwrap.wrap(stats.LEGEND + f"; better = B lower (higher for {higher})", WIDTH),
             "all (stratified): each scenario counts once; errors as the ratio B / A", ""]
    for group in _column_groups(result, table_keys(result)):
        lines += [*_block(result, group), ""]
    counts = [f"{k} {stats.counts_text(c)} (Holm: {c['better_holm']}b {c['worse_holm']}w)"
              for k, c in result["counts"].items()]
    chance = stats.expected_by_chance(len(result["labels"]))
    lines += _wrapped(f"verdicts for B over {len(result['labels'])} labels (chance alone gives "
                      f"at most {chance:.1f} b and {chance:.1f} w per metric):", counts)
    lines += [f"note: {n}" for n in result["notes"]]
    return "\n".join(lines)
