"""A bench scenario over seeds, as `bench --json` writes it: each metric's mean with its spread
and 95% interval, the departure rate with its exact interval, paired verdicts, and every
episode's own report so that `lanekeep compare` can pair two runs seed by seed.

The document of each bench label: KEYS_HELP below (`lanekeep bench --help` prints it).
Intervals and verdicts: lanekeep/scoring/statistics.py (t over seeds, on the log scale for
errors; exact tests for departures; each metric's margin). With one seed every interval is
null; below three seeds every verdict is "too few".
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence
from typing import Any

from lanekeep.report.json_io import report_document, strict, with_metadata
from lanekeep.scoring import statistics as stats
from lanekeep.scoring.metrics import EPISODE_METRICS, EpisodeReport, SourceReport

KEYS_HELP = """\
bench --json: one document per label (a scenario, or "SCENARIO@MODEL" for a model-only loop):
  schema_version, lanekeep_version, scenario_sha256   as every report (json_io.METADATA_KEYS)
  seed            the seed when one ran, else null (see `seeds`)
  scenario, label, seeds, n       the scenario's name, the bench key, the seeds, their count
  mode, overrides                 the estimation mode and the command line's changes
                                  (front_detectors, reference_detector, controller, settings)
  sources.NAME.KEY                mean over seeds of SourceReport's KEY (rmse_cm, max_cm,
                                  ade_cm, fde_cm, drift_cm, valid_share), NaN runs left out
  sources.NAME.KEY_sd, KEY_ci95   sample sd and a 95% interval [lo, hi]: for the errors
                                  (rmse, max, ade, fde) the geometric mean's (log scale, never
                                  below 0), given as KEY_gmean; else the mean's t interval
  car_rms_cm, car_max_cm, lane_departures, mmae_switches, reference_repairs, no_estimate_s
                                  means, each with _sd and _ci95 likewise (car_* log scale)
  departure_rate, departure_rate_ci95, departed_episodes
                                  share of episodes with >= 1 lane departure, its
                                  Clopper-Pearson 95% interval, the count
  failed_episodes, failure_rate, failure_rate_ci95
                                  episodes that failed: a lane departure, or an end off the
                                  road, in a collision or in unstable physics (a collision
                                  can end a drive before it departs), their share and its
                                  Clopper-Pearson 95% interval
  collided_episodes, collision_rate, collision_rate_ci95
                                  episodes that ended in a collision, their share and its
                                  Clopper-Pearson 95% interval
  min_ttc_s, min_gap_m            the lowest over the seeds of each episode's smallest time
                                  to collision and gap to the vehicle ahead in the car's path
                                  (null: never closing on / never having one)
  min_ttc_s_mean, _ci95, _n       the mean over the episodes that closed on a vehicle of
  min_gap_m_mean, _ci95, _n       their smallest TTC (gap), its 95% t interval (cut at 0)
                                  and how many
  hard_braking_events             mean per episode, with _sd and _ci95 (decelerations of
                                  0.4 g or more, one per braking)
  completed, passed               every episode completed / met its criteria
  completed_episodes, passed_episodes
  wall_s                          the episodes' wall time, summed
  paired.fused_vs.MODEL:track     {diff_cm, ci95, verdict, n, margin, p_worse, p_better,
                                  detectable, dropped, ratio, ratio_ci95}: fused RMSE - the
                                  model's own track RMSE per seed, both over the steps where
                                  both had an estimate where the episodes say so
                                  (common_share: that share of the steps); verdict for fused
                                  against the rmse margin (statistics.MARGINS)
  paired.mmae_loop_vs.MODEL.KEY   with --single-model: the MMAE loop's car_rms_cm, car_max_cm
                                  minus the loop driven by MODEL alone (paired, margins), and
                                  lane_departures (episodes with one) and failed (episodes
                                  that failed: scoring/metrics.drive_failed), each by
                                  McNemar's exact test
  episodes                        each seed's report document (as `run --json` writes it)
"""
SOURCE_KEYS = tuple(f.name for f in dataclasses.fields(SourceReport))
EPISODE_KEYS = EPISODE_METRICS
LOOP_KEYS = ("car_rms_cm", "car_max_cm", "lane_departures")  # MMAE loop vs a model alone
HIGHER_IS_BETTER = frozenset({"valid_share", "min_ttc_s", "min_gap_m"})


def _spread_keys(key: str, values: Sequence[float]) -> dict[str, Any]:
    s = stats.spread([float(v) for v in values], stats.is_log_scale(key))
    out = {key: s.mean, f"{key}_sd": s.sd, f"{key}_ci95": list(s.ci95)}
    if s.log_scale:
        out[f"{key}_gmean"] = s.center
    return out


def summarise(label: str, reports: Sequence[EpisodeReport], scenario,
              overrides: dict | None = None, mode: str | None = None,
              single_model: dict[str, Sequence[EpisodeReport]] | None = None) -> dict:
    """The document of `label` over its seeds' `reports` (in seed order); `single_model` maps
    a front model to its model-only loop's reports on the same seeds, for the paired block."""
    if not reports:
        raise ValueError(f"{label}: no episode to summarise")
    seeds = [r.seed for r in reports]
    if len(set(seeds)) != len(seeds):
        raise ValueError(f"{label}: a seed repeats in {seeds}")
    names = list(reports[0].sources)
    sources = {}
    for name in names:
        entry: dict[str, Any] = {}
        for key in SOURCE_KEYS:
            entry.update(_spread_keys(key, [getattr(r.sources[name], key) for r in reports]))
        sources[name] = entry
    departed = sum(1 for r in reports if r.lane_departures > 0)
    failed = sum(1 for r in reports if r.failed)
    doc: dict[str, Any] = {
        "scenario": reports[0].scenario, "label": label, "seeds": seeds, "n": len(reports),
        "mode": mode, "overrides": overrides or {}, "sources": sources,
    }
    for key in EPISODE_KEYS:
        doc.update(_spread_keys(key, [getattr(r, key) for r in reports]))
    doc.update({
        "departure_rate": departed / len(reports),
        "departure_rate_ci95": list(stats.rate_interval(departed, len(reports))),
        "departed_episodes": departed,
        "failure_rate": failed / len(reports),
        "failure_rate_ci95": list(stats.rate_interval(failed, len(reports))),
        "failed_episodes": failed,
        **safety_keys(reports),
        "completed": all(r.completed for r in reports),
        "completed_episodes": sum(1 for r in reports if r.completed),
        "passed": all(r.passed for r in reports),
        "passed_episodes": sum(1 for r in reports if r.passed),
        "wall_s": sum(r.wall_s for r in reports),
        "paired": paired_block(reports, single_model),
        "episodes": [report_document(r, scenario) for r in reports],
    })
    return strict(with_metadata(doc, scenario, seed=seeds[0] if len(seeds) == 1 else None)
                  | ({"seed": None} if len(seeds) > 1 else {}))


def safety_keys(reports: Sequence[EpisodeReport]) -> dict[str, Any]:
    """Collisions as a rate with its exact interval, the lowest minimum TTC and gap over the
    seeds (the worst episode is what safety asks about), hard braking events' mean."""
    collided = sum(1 for r in reports if r.collisions > 0)
    gaps = [r.min_gap_m for r in reports if r.min_gap_m is not None]
    ttcs = [r.min_ttc_s for r in reports if math.isfinite(r.min_ttc_s)]
    return {"collided_episodes": collided, "collision_rate": collided / len(reports),
            "collision_rate_ci95": list(stats.rate_interval(collided, len(reports))),
            "min_ttc_s": min(r.min_ttc_s for r in reports),
            "min_gap_m": min(gaps) if gaps else None,
            **_mean_keys("min_ttc_s", ttcs), **_mean_keys("min_gap_m", gaps),
            **_spread_keys("hard_braking_events", [r.hard_braking_events for r in reports])}


def _mean_keys(key: str, values: Sequence[float]) -> dict[str, Any]:
    """A per-episode minimum's mean over the episodes that had one, with its t interval cut
    at zero: a time or a gap is never negative, and the part of an interval outside what the
    mean can be holds none of its coverage (one drive that never closes far from the others,
    148.5 s beside 7-15 s, gave [-209.3, 506.2] s)."""
    s = stats.spread([float(v) for v in values])
    lo, hi = s.ci95
    ci = [max(lo, 0.0) if math.isfinite(lo) else lo, hi]
    return {f"{key}_mean": s.mean if values else None,
            f"{key}_mean_ci95": ci if values else None, f"{key}_n": len(values)}


def paired_block(reports: Sequence[EpisodeReport],
                 single_model: dict[str, Sequence[EpisodeReport]] | None = None) -> dict:
    """Fused vs each model's own track (RMSE, per seed); the MMAE loop vs each model-only
    loop (car error and departures, per seed) where those ran."""
    tracks = [n for n in reports[0].sources if n.endswith(":track")]
    block: dict[str, Any] = {"fused_vs": {t: fused_vs_track(reports, t) for t in tracks}}
    if single_model:
        loops = {}
        for model, alone in single_model.items():
            by_seed = {r.seed: r for r in alone}
            pairs = [(r, by_seed[r.seed]) for r in reports if r.seed in by_seed]
            loops[model] = {
                key: stats.paired([float(getattr(a, key)) for a, _ in pairs],
                                  [float(getattr(b, key)) for _, b in pairs],
                                  metric=key).as_dict("cm")
                for key in LOOP_KEYS if key != "lane_departures"}
            loops[model]["lane_departures"] = stats.paired_events(
                [a.lane_departures > 0 for a, _ in pairs],
                [b.lane_departures > 0 for _, b in pairs]).as_dict("")
            # a drive that hit a car or left the road before a wheel crossed a line failed too
            loops[model]["failed"] = stats.paired_events(
                [a.failed for a, _ in pairs], [b.failed for _, b in pairs]).as_dict("")
        block["mmae_loop_vs"] = loops
    return block


def fused_vs_track(reports: Sequence[EpisodeReport], track: str) -> dict[str, Any]:
    """Fused RMSE against a model's own track, paired over seeds: on the steps where both had
    an estimate where the episode reports carry those (`fused_vs_track`), else each over its
    own valid steps (older reports), with the common steps' mean share."""
    fused, other, shares = [], [], []
    for r in reports:
        common = r.fused_vs_track.get(track)
        if common is not None:
            fused.append(common.rmse_a_cm)
            other.append(common.rmse_b_cm)
            shares.append(common.share)
        else:
            fused.append(r.sources["fused"].rmse_cm)
            other.append(r.sources[track].rmse_cm)
    out = stats.paired(fused, other, metric="rmse_cm").as_dict("cm")
    out["common_share"] = sum(shares) / len(shares) if shares else None
    return out


def interval_text(mean: float | None, ci: Sequence[float | None] | None, digits: int = 2
                  ) -> str:
    """"0.52 [0.48, 0.57]", or the mean alone where there is no interval, "-" for none."""
    if mean is None or (isinstance(mean, float) and math.isnan(mean)):
        return "-"
    if not ci or ci[0] is None or ci[1] is None or any(math.isnan(c) for c in ci):
        return f"{mean:.{digits}f}"
    return f"{mean:.{digits}f} [{ci[0]:.{digits}f}, {ci[1]:.{digits}f}]"
