"""The regression gate: this bench against a baseline bench on the same seeds.

Why a second mechanism beside the acceptance criteria: the criteria state requirements (the
car stays in its lane; lateral error and fused RMSE a researcher would accept), which a loop
can meet while getting worse. The gate answers the other question, "did my change make the
loop worse by more than the margin?", from paired seeds: `lanekeep bench --baseline BASE.json`
runs BASE's scenarios on BASE's seeds, pairs each episode with BASE's, and fails a scenario
whose metric is `worse` beyond its margin (lanekeep/report/compare.py, the statistics in
lanekeep/scoring/statistics.py), where that claim survives Holm's adjustment over the
scenarios of the metric: with 16 scenarios a gate of raw 2.5% tests would fail a loop that
sits at the margin everywhere about a third of the time; Holm keeps any false fail of a metric
at 2.5%. A raw `worse` that Holm does not confirm is printed, not failed.
`--write-baseline F` records a bench as a baseline.

A scenario whose `[criteria]` set `bad_episode_fused_rmse_m` is two-mode (a lead car hides
the markings on some drives and not on others); its fused RMSE is judged by its rate of bad
episodes (McNemar's exact test) instead of a mean over two modes.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

from lanekeep.report.compare import (
    IncomparableRuns,
    check_bench,
    compare_runs,
    compare_table,
    parse_metric,
)
from lanekeep.scoring import statistics as stats

# `failed` beside the departures: a drive that newly ends in a collision or off the road before
# it departs is a regression the departure count alone would not see.
GATE_METRICS = ("fused.rmse_cm", "car_rms_cm", "car_max_cm", "lane_departures", "failed")


@dataclass(frozen=True)
class GateFailure:
    """One scenario's metric that got worse beyond its margin."""

    label: str
    metric: str
    entry: dict[str, Any]

    def text(self) -> str:
        e = self.entry
        if e.get("ci95") and e["ci95"][0] is not None and math.isfinite(e["ci95"][0]):
            return (f"{self.label}: {self.metric} {e['diff']:+.3g} [{e['ci95'][0]:+.3g}, "
                    f"{e['ci95'][1]:+.3g}] beyond the margin {e.get('margin', 0):.3g}")
        return f"{self.label}: {self.metric} {e['verdict']} (p {e.get('p_worse', math.nan):.3g})"


@dataclass(frozen=True)
class GateResult:
    """The comparison behind the gate, the failures and the two-mode scenarios' rates."""

    comparison: dict[str, Any]
    failures: tuple[GateFailure, ...]
    two_mode: dict[str, dict[str, Any]] = field(default_factory=dict)
    unconfirmed: tuple[GateFailure, ...] = ()  # worse, but not after Holm: shown, not failed

    @property
    def passed(self) -> bool:
        return not self.failures


def baseline_plan(base: dict, names: Sequence[str] = ()) -> dict[str, list[int]]:
    """The scenarios and seeds a bench against `base` runs: every main label of the baseline
    (model-only labels "SCENARIO@MODEL" aside), or those of `names`; IncomparableRuns naming a
    scenario the baseline lacks."""
    run = check_bench(base, "baseline")
    labels = {label: sorted(doc["seeds"]) for label, doc in run.docs.items() if "@" not in label}
    missing = [n for n in names if n not in labels]
    if missing:
        raise IncomparableRuns(f"the baseline has no scenario {', '.join(missing)} (it has "
                               f"{', '.join(labels)})")
    return {n: labels[n] for n in (names or labels)}


def bad_episodes(doc: dict, limit_m: float) -> list[bool]:
    """Per seed (in the document's episode order), whether the fused RMSE exceeded the limit
    (or there was no fused estimate at all)."""
    out = []
    for e in sorted(doc["episodes"], key=lambda e: e["seed"]):
        rmse = ((e.get("sources") or {}).get("fused") or {}).get("rmse_cm")
        out.append(rmse is None or rmse / 100.0 > limit_m)
    return out


def regression_gate(base: dict, new: dict, metrics: Sequence[str] = GATE_METRICS,
                    margins: dict[str, stats.Margin] | None = None,
                    two_mode: dict[str, float] | None = None) -> GateResult:
    """`new` against `base` on their common labels (`new`'s), each metric's verdict; the gate
    fails on every `worse`. `two_mode`: label -> its `bad_episode_fused_rmse_m` (m).
    IncomparableRuns if they cannot be paired."""
    limits = two_mode or {}
    base = {label: doc for label, doc in base.items() if label in new}
    comparison = compare_runs(base, new, [parse_metric(m) for m in metrics], "baseline",
                              "this run", margins)
    judged: dict[str, list[tuple[str, str, dict]]] = {}  # metric -> (label, name, entry)
    rates_of = {}
    for label, entries in comparison["labels"].items():
        limit = limits.get(label)
        for key, entry in entries.items():
            name = key
            if limit is not None and key == "fused.rmse_cm":
                p = stats.paired_events(bad_episodes(new[label], limit),
                                        bad_episodes(base[label], limit))
                entry = {"limit_m": limit, **p.as_dict("rate"),
                         "baseline_bad": sum(bad_episodes(base[label], limit)),
                         "this_run_bad": sum(bad_episodes(new[label], limit))}
                rates_of[label] = entry
                name = f"bad episodes (fused RMSE > {100 * limit:g} cm)"
            judged.setdefault(key, []).append((label, name, entry))
    failures, unconfirmed = [], []
    for rows in judged.values():
        adjusted = stats.holm([_p(entry.get("p_worse")) for _, _, entry in rows])
        for (label, name, entry), p in zip(rows, adjusted, strict=True):
            if entry["verdict"] != "worse":
                continue
            target = failures if p < stats.ALPHA_ONE_SIDED else unconfirmed
            target.append(GateFailure(label, name, {**entry, "p_worse_holm": p}))
    return GateResult(comparison, tuple(failures), rates_of, tuple(unconfirmed))


def _p(value: Any) -> float:
    return float(value) if isinstance(value, (int, float)) and math.isfinite(value) else 1.0


def gate_text(gate: GateResult) -> str:
    """The comparison table, the two-mode scenarios' rates and the gate's verdict."""
    lines = [compare_table(gate.comparison), ""]
    for label, r in gate.two_mode.items():
        n = r["n"]
        lines.append(f"{label} (two-mode): bad episodes (fused RMSE > {100 * r['limit_m']:g} "
                     f"cm) baseline {r['baseline_bad']}/{n}, this run {r['this_run_bad']}/{n}: "
                     f"{r['verdict']} (McNemar exact; replaces the fused RMSE's verdict)")
    if gate.passed:
        lines.append("regression gate: PASS (no scenario worse beyond its margin after Holm)")
    else:
        lines.append(f"regression gate: FAIL ({len(gate.failures)} worse beyond the margin, "
                     "Holm-adjusted over the scenarios)")
        lines += [f"  {f.text()}" for f in gate.failures]
    if gate.unconfirmed:
        lines.append("worse on their own, not after Holm (not failed; rerun on fresh seeds "
                     "to tell):")
        lines += [f"  {f.text()} (Holm p {f.entry['p_worse_holm']:.3g})"
                  for f in gate.unconfirmed]
    return "\n".join(lines)
