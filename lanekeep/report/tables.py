"""The terminal tables of `run` and `bench`: an episode's errors per source, the per-scenario
summary, frame-to-frame drift, the model-only loops, the intervals over seeds, and the closing
verdict lines with the exit code.

By default every table fits a terminal of WIDTH columns (sources as rows, the less used columns
left out); `wide=True` (`--wide`) gives the full tables, which run to ~190 columns.
"""

from __future__ import annotations

import math
import re
import textwrap
from typing import Protocol

from lanekeep.report.seed_summary import interval_text
from lanekeep.scoring import criteria as criteria_mod
from lanekeep.scoring import statistics as stats
from lanekeep.scoring.metrics import FAILED_STATUSES, EpisodeReport


class LoopJob(Protocol):
    """What the model-only table needs of a bench job (lanekeep.loop.runner.BenchJob)."""

    scenario: str
    front_detectors: tuple[str, ...] | None

    @property
    def label(self) -> str: ...


WIDTH = 100  # columns the default tables fit
# (row label, SourceReport attribute) of an episode's table, in the paper's Table 3-4 order
EPISODE_METRICS = (("RMSE", "rmse_cm"), ("max", "max_cm"), ("ADE", "ade_cm"), ("FDE", "fde_cm"),
                   ("drift", "drift_cm"), ("valid %", "valid_share"))


def episode_table(report: EpisodeReport, wide: bool = False) -> str:
    """One episode's errors (cm) per source, then the car's line, the footnote and the
    criteria. Compact (default): one row per source, so that any number of detectors fits
    WIDTH columns; wide: the paper's layout, one column per source (EpisodeReport.table)."""
    full = report.table()
    if wide:
        return full
    names = list(report.sources)
    name_w = max(12, *(len(n) + 2 for n in names))
    header = f"{'(cm)':<{name_w}}" + "".join(f"{label:>9}" for label, _ in EPISODE_METRICS)
    lines = [header]
    for name in names:
        source = report.sources[name]
        cells = []
        for _, key in EPISODE_METRICS:
            value = getattr(source, key) * (100.0 if key == "valid_share" else 1.0)
            cells.append(f"{'-' if math.isnan(value) else f'{value:.2f}':>9}")
        lines.append(f"{name:<{name_w}}" + "".join(cells))
    # The lines below the grid are the full table's: the car, the footnote, the criteria.
    rest = full.splitlines()
    rest = rest[next(i for i, line in enumerate(rest) if line.startswith("car: ")):]
    for line in rest:
        lines.extend(_fold(line))
    return "\n".join(lines)


def _fold(line: str) -> list[str]:
    """`line` in lines of at most WIDTH columns, broken after a "; " or before a "  [note]"
    where it can be (between two facts rather than inside one), the rest indented by two."""
    if len(line) <= WIDTH:
        return [line]
    indent = line[: len(line) - len(line.lstrip())] + "  "
    pieces = re.split(r"(?<=;) |  (?=\[)", line)
    out = [pieces[0]]
    for piece in pieces[1:]:
        if len(out[-1]) + 1 + len(piece) <= WIDTH:
            out[-1] += " " + piece
        else:
            out.append(indent + piece)
    return [folded for piece in out for folded in
            (textwrap.wrap(piece, WIDTH, subsequent_indent=indent, break_on_hyphens=False)
             or [""])]


def bench_verdict(reports: dict[str, EpisodeReport], main_labels: list[str],
                  unit: str = "scenarios") -> tuple[list[str], int]:
    """The bench's closing lines and exit code. The code judges the scenarios as configured
    (`main_labels`); `--single-model` loops are a diagnostic (one detector driving alone),
    judged by the same criteria and reported, but not counted."""
    failed = [label for label, r in reports.items() if not r.passed]
    lines = [f"FAILED {label}: {criteria_mod.failure_message(reports[label])}"
             for label in failed]
    main_failed = [label for label in failed if label in main_labels]
    lines.append(f"criteria: {len(main_labels) - len(main_failed)} of {len(main_labels)} "
                 f"{unit} passed")
    if len(main_labels) > 1:  # what a rule's false-fail rate can be, read on these episodes
        lo, hi = stats.rate_interval(len(main_failed), len(main_labels))
        lines.append(f"observed fail rate {len(main_failed)}/{len(main_labels)} = "
                     f"{len(main_failed) / len(main_labels):.3f} [{lo:.3f}, {hi:.3f}] "
                     "(Clopper-Pearson 95%)")
    extra = len(reports) - len(main_labels)
    if extra:
        lines.append(f"model-only loops: {extra - (len(failed) - len(main_failed))} of {extra} "
                     "passed (not counted in the exit code)")
    return lines, (1 if main_failed else 0)


def _best(sources: dict, names: list[str]) -> tuple[str, float]:
    """The source with the lowest offset RMSE among `names` (NaN counts as worst)."""
    rmse = {n: sources[n].rmse_cm for n in names}
    name = min(rmse, key=lambda n: math.inf if math.isnan(rmse[n]) else rmse[n])
    return name, rmse[name]


def _verdict(r: EpisodeReport) -> str:
    """The summary's last column: "pass", "FAIL" or the status of an episode that stopped."""
    if r.status != "completed":
        return r.status.upper().replace("_", " ")
    return ("pass" if r.passed else "FAIL") if r.criteria else "-"


def summary_table(reports: list[EpisodeReport], wide: bool = False) -> str:
    """One line per scenario: fused vs the best front model's own track (like for like: both
    Kalman estimates at the same look-ahead) and its best raw detection; reference; safety;
    the criteria's verdict. Columns are as wide as their longest name: nothing is cut.
    Compact (default): without the best raw detection and the MMAE switches."""
    rows = []
    for r in reports:
        tracks = [k for k in r.sources if k.endswith(":track")]
        raws = [k[: -len(":track")] for k in tracks]
        rows.append((r, _best(r.sources, tracks), _best(r.sources, raws)))
    names = [n for _, (t, _), (w, _) in rows for n in (t.split(":")[0], w)] or [""]
    name_w = max(len(n) for n in names)
    scen_w = max([28, *(len(r.scenario) + 2 for r in reports)])
    best_w = name_w + 11  # "%8.1f (name)"
    if not wide:
        scen_w, best_w = max([10, *(len(r.scenario) + 2 for r in reports)]), name_w + 10
    header = (f"{'scenario':<{scen_w}}{'fused':>8}{'best track':>{best_w}}"
              + (f"{'best raw':>{best_w}}" if wide else "")
              + f"{'reference':>11}{'car RMS':>9}{'depart':>8}"
              + (f"{'switch':>8}" if wide else "") + "  result")
    lines = [header, "-" * len(header)]
    value_w = best_w - name_w - 3  # "value (name)"
    for r, (track_name, track), (raw_name, raw) in rows:
        lines.append(
            f"{r.scenario:<{scen_w}}{r.sources['fused'].rmse_cm:>8.1f}"
            f"{track:>{value_w}.1f} ({track_name.split(':')[0]:>{name_w}})"
            + (f"{raw:>{value_w}.1f} ({raw_name:>{name_w}})" if wide else "")
            + f"{r.sources['reference'].rmse_cm:>11.1f}{r.car_rms_cm:>9.1f}"
            f"{r.lane_departures:>8d}" + (f"{r.mmae_switches:>8d}" if wide else "")
            + f"  {_verdict(r)}"
        )
    note = ("(offset RMSE in cm; track = a model's own Kalman track at the fused output's "
            "look-ahead; fused = the MMAE output"
            + ("; raw = its detections, on the steps it had one)" if wide else
               "; --wide adds each model's raw detections and the MMAE switches)"))
    lines.extend(textwrap.wrap(note, max(WIDTH, len(header))))
    return "\n".join(lines)


def _finite_mean(values: list[float]) -> float:
    finite = [v for v in values if math.isfinite(v)]
    return sum(finite) / len(finite) if finite else math.nan


def drift_table(reports: list[EpisodeReport]) -> str:
    """Paper 000's tracking claim, per scenario: frame-to-frame drift (metrics.SourceReport)
    of each front model's raw detections and of its own Kalman track, and of the fused
    output; the change is the tracks' mean against the raw detections' mean."""
    rows = []
    for r in reports:
        tracks = [k for k in r.sources if k.endswith(":track")]
        raw = [r.sources[k[: -len(":track")]].drift_cm for k in tracks]
        track = [r.sources[k].drift_cm for k in tracks]
        rows.append((r.scenario, _finite_mean(raw), _finite_mean(track),
                     r.sources["fused"].drift_cm))
    scen_w = max([28, *(len(n) + 2 for n, *_ in rows)])
    header = f"{'scenario':<{scen_w}}{'raw':>8}{'tracks':>8}{'change':>9}{'fused':>8}"
    lines = ["frame-to-frame drift (cm; mean over the front models)", header, "-" * len(header)]
    for name, raw, track, fused in rows:
        change = f"{100.0 * (track - raw) / raw:+.0f}%" if raw > 0 else "-"
        lines.append(f"{name:<{scen_w}}{raw:>8.2f}{track:>8.2f}{change:>9}{fused:>8.2f}")
    raws = [raw for _, raw, _, _ in rows if math.isfinite(raw)]
    tracks = [track for _, _, track, _ in rows if math.isfinite(track)]
    if raws and tracks:
        mean_raw, mean_track = _finite_mean(raws), _finite_mean(tracks)
        lines.append(f"{'mean':<{scen_w}}{mean_raw:>8.2f}{mean_track:>8.2f}"
                     f"{100.0 * (mean_track - mean_raw) / mean_raw:>+8.0f}%")
    lines.append("(drift: RMS over consecutive steps of the offset's change minus the true "
                 "change; paper 000 reports -12% for its Kalman filter)")
    return "\n".join(lines)


def single_model_table(jobs: list[LoopJob], reports: dict[str, EpisodeReport]) -> str:
    """The closed loop driven by the MMAE beside the same loop driven by each front model
    alone (the paper's "model-only system"): the car's own lateral error and departures."""
    def loop(job: LoopJob) -> str:
        return "+".join(job.front_detectors) + " only" if job.front_detectors else "MMAE"

    scen_w = max([28, *(len(j.label) + 2 for j in jobs if j.front_detectors is None)])
    loop_w = max([22, *(len(loop(j)) + 2 for j in jobs)])
    header = (f"{'scenario':<{scen_w}}{'loop':>{loop_w}}{'car RMS':>9}{'car max':>9}"
              f"{'depart':>8}  result")
    lines = ["closed loop: MMAE vs each front model alone", header, "-" * len(header)]
    for main in (j for j in jobs if j.front_detectors is None):
        alone = [j for j in jobs if j.scenario == main.scenario and j.front_detectors]
        for job in [main, *alone]:
            r = reports[job.label]
            lines.append(f"{main.label if job is main else '':<{scen_w}}{loop(job):>{loop_w}}"
                         f"{r.car_rms_cm:>9.1f}{r.car_max_cm:>9.1f}{r.lane_departures:>8d}"
                         f"  {_verdict(r)}")
    lines.append("(car = its true lateral offset from the lane centre, cm)")
    return "\n".join(lines)


def interval_table(docs: list[dict], wide: bool = False) -> str:
    """One line per scenario over its seeds (lanekeep/report/seed_summary.py documents):
    fused RMSE and the car's RMS with 95% intervals, the best own track by mean, the fused
    output's paired verdicts against the model tracks, departures as a rate with its exact
    interval, and how many episodes met the criteria. Compact (default): without the best
    track and the departures' interval."""
    if not wide:
        return _compact_interval_table(docs)
    scen_w = max([28, *(len(d["label"]) + 2 for d in docs)])
    model_w = max([8, *(len(k) - len(":track") for d in docs for k in d["sources"]
                        if k.endswith(":track"))])
    best_w = model_w + 10  # "0.48 (lanenet)"
    header = (f"{'scenario':<{scen_w}}{'n':>3}  {'fused RMSE [95% CI]':<22}{'best track':<{best_w}}"
              f"{'fused vs tracks':<17}{'car RMS [95% CI]':<22}{'departed':<18}{'failed':<8}passed")
    lines = [header, "-" * len(header)]
    for d in docs:
        tracks = {k: v for k, v in d["sources"].items() if k.endswith(":track")}
        best = min(tracks, key=lambda k: math.inf if tracks[k]["rmse_cm"] is None
                   else tracks[k]["rmse_cm"]) if tracks else None
        counts = stats.count_verdicts([p["verdict"] for p in d["paired"]["fused_vs"].values()])
        fused = d["sources"]["fused"]
        best_text = (f"{tracks[best]['rmse_cm']:.2f} ({best[: -len(':track')]})"
                     if best and tracks[best]["rmse_cm"] is not None else "-")
        lo, hi = d["departure_rate_ci95"]
        rate = (f"{d['departed_episodes']}/{d['n']} [{lo:.2f}, {hi:.2f}]" if hi is not None
                else f"{d['departed_episodes']}/{d['n']}")
        lines.append(
            f"{d['label']:<{scen_w}}{d['n']:>3}  "
            f"{_center_text(fused, 'rmse_cm'):<22}{best_text:<{best_w}}"
            f"{stats.counts_text(counts):<17}{_center_text(d, 'car_rms_cm', 1):<22}"
            f"{rate:<18}{_failed_text(d):<8}{d['passed_episodes']}/{d['n']}")
    lines.extend(textwrap.wrap(_fused_vs_total(docs), WIDTH))
    lines.extend(textwrap.wrap(
        "(cm; geometric mean over seeds [95% interval, log scale]; departed = episodes with a "
        "lane departure [Clopper-Pearson 95%]; failed = " + FAILED_TEXT + "; verdicts per "
        "scenario: " + stats.LEGEND
        + "; margins: docs/statistics.md#margins)", WIDTH))
    return "\n".join(lines)


FAILED_TEXT = ("episodes that departed or ended off the road, in a collision or in unstable "
               "physics")


def _failed_text(doc: dict) -> str:
    """"1/5": the failed episodes; "-" for a document written before lanekeep counted them."""
    failed = doc.get("failed_episodes")
    return "-" if failed is None else f"{failed}/{doc['n']}"


def _center_text(doc: dict, key: str, digits: int = 2) -> str:
    """A metric's centre over seeds and its interval: the geometric mean where the interval is
    on the log scale (errors), else the mean."""
    center = doc.get(f"{key}_gmean", doc.get(key))
    return interval_text(center, doc.get(f"{key}_ci95"), digits)


def _fused_vs_total(docs: list[dict]) -> str:
    """The verdicts of the fused output against each model's own track, over all scenarios."""
    verdicts = [p["verdict"] for d in docs for p in d["paired"]["fused_vs"].values()]
    total = stats.count_verdicts(verdicts)
    if total["too few"] == len(verdicts):
        return ("fused vs each model's own track: no verdict (fewer than "
                f"{stats.MIN_PAIRS} seeds; run bench with --seeds N)")
    shown = ", ".join(f"{n} {v}" for v, n in total.items() if n or v in stats.CLAIMS)
    chance = stats.expected_by_chance(len(verdicts))
    return (f"fused vs each model's own track, paired over seeds: {shown} (of "
            f"{len(verdicts)}; about {chance:.1f} better and {chance:.1f} worse expected by "
            "chance alone)")


def _compact_interval_table(docs: list[dict]) -> str:
    scen_w = max([10, *(len(d["label"]) + 2 for d in docs)])
    header = (f"{'scenario':<{scen_w}}{'n':>3}  {'fused RMSE [95% CI]':<20}{'vs tracks':<11}"
              f"{'car RMS [95% CI]':<18}{'departed':<10}passed")
    lines = [header, "-" * len(header)]
    for d in docs:
        counts = stats.count_verdicts([p["verdict"] for p in d["paired"]["fused_vs"].values()])
        fused = d["sources"]["fused"]
        verdicts = stats.counts_text(counts) + " "
        lines.append(
            f"{d['label']:<{scen_w}}{d['n']:>3}  "
            f"{_center_text(fused, 'rmse_cm'):<19} {verdicts:<11}"
            f"{_center_text(d, 'car_rms_cm', 1):<17} "
            f"{str(d['departed_episodes']) + '/' + str(d['n']):<10}"
            f"{d['passed_episodes']}/{d['n']}")
    lines.extend(textwrap.wrap(_fused_vs_total(docs), WIDTH))
    lines.extend(textwrap.wrap(
        "(cm; geometric mean over seeds [95% interval, log scale]; departed = episodes with a "
        "lane departure; verdicts per scenario: " + stats.LEGEND + "; margins: "
        "docs/statistics.md#margins; --wide adds the best track and the departures' "
        "Clopper-Pearson interval and the failed episodes)", WIDTH))
    lines.extend(textwrap.wrap(_failed_without_departing(docs), WIDTH))
    return "\n".join(lines)


def _failed_without_departing(docs: list[dict]) -> str:
    """The drives that failed without a departure (a collision, off the road, unstable
    physics), which the departed column does not count: "" when there is none."""
    ended = [f"{d['label']} seed {e['seed']} ({e['status'].replace('_', ' ')})"
             for d in docs for e in d.get("episodes", [])
             if not e.get("lane_departures") and e.get("status") in FAILED_STATUSES]
    return ("failed without a departure (not in departed): " + ", ".join(ended)
            if ended else "")


def _has_safety(doc: dict) -> bool:
    """Whether a scenario's document has anything to say about safety: a collision, a
    vehicle ahead in the car's path or a hard braking (a document from before these: no)."""
    return bool(doc.get("collided_episodes") or doc.get("min_gap_m") is not None
                or (doc.get("hard_braking_events") or 0) > 0)


def safety_table(docs: list[dict]) -> str:
    """One line per scenario over its seeds (lanekeep/report/seed_summary.py documents): the
    episodes that hit another vehicle, the lowest minimum time to collision and gap to the
    vehicle ahead in the car's path, hard braking events per episode. "" when no scenario had
    a vehicle ahead, a hard braking or a collision (lane keeping alone: nothing to say)."""
    if not any(_has_safety(d) for d in docs):
        return ""
    scen_w = max([10, *(len(d["label"]) + 2 for d in docs)])
    header = (f"{'scenario':<{scen_w}}{'n':>3}  {'collided':<10}{'min TTC s':>11}"
              f"{'mean [95% CI]':>19}{'min gap m':>11}{'mean [95% CI]':>19}{'hard brake':>11}")
    lines = ["safety among other vehicles", header, "-" * len(header)]
    def number(value: float | None) -> str:
        return "-" if value is None else f"{value:.1f}"

    def mean(d: dict, key: str) -> str:
        value, ci = d.get(f"{key}_mean"), d.get(f"{key}_mean_ci95")
        if value is None or ci is None:
            return "-"
        # One episode with a value has no interval: its bounds are null in strict JSON.
        return f"{number(value)} [{number(ci[0])}, {number(ci[1])}]".replace("nan", "-")

    for d in docs:
        collided = d.get("collided_episodes")
        collided_text = "-" if collided is None else f"{collided}/{d['n']}"
        lines.append(f"{d['label']:<{scen_w}}{d['n']:>3}  {collided_text:<10}"
                     f"{number(d.get('min_ttc_s')):>11} {mean(d, 'min_ttc_s'):>18}"
                     f"{number(d.get('min_gap_m')):>11} {mean(d, 'min_gap_m'):>18}"
                     f"{number(d.get('hard_braking_events')):>11}")
    lines.extend(textwrap.wrap(
        "(collided = episodes that hit another vehicle (each ends there and fails); min TTC, "
        "min gap: the lowest over the seeds, to the vehicle ahead in the car's path, then the "
        "mean of each episode's smallest over the episodes that had one, with its 95% t "
        "interval cut at 0; - = never closing on one / never one ahead; hard brake = "
        "decelerations of 0.4 g or more, one per braking, mean per episode)", WIDTH))
    return "\n".join(lines)


def paired_table(docs: list[dict]) -> str:
    """Each paired comparison of the bench: fused minus each model's own track (RMSE), and,
    with --single-model, the MMAE loop minus each model-only loop (car RMS, max, departures)."""
    rows = []
    for d in docs:
        for track, p in d["paired"]["fused_vs"].items():
            rows.append((d["label"], f"fused - {track} RMSE", p["diff_cm"], p))
        for model, keys in d["paired"].get("mmae_loop_vs", {}).items():
            for key, p in keys.items():
                rows.append((d["label"], f"MMAE - {model} alone: {key}",
                             p.get("diff_cm", p.get("diff")), p))
    scen_w = max([28, *(len(d["label"]) + 2 for d in docs)])
    comp_w = max([34, *(len(r[1]) + 2 for r in rows)])
    header = (f"{'scenario':<{scen_w}}{'comparison':<{comp_w}}{'diff [95% CI]':<28}"
              f"{'margin':<8}verdict")
    lines = ["paired over seeds (difference = first - second; negative = first lower)", header,
             "-" * len(header)]
    last = None
    for label, what, diff, p in rows:
        margin = p.get("margin")
        margin_text = f"{margin:.2f}" if margin is not None and math.isfinite(margin) else "-"
        detect = p.get("detectable")
        note = (f" (detectable: {detect:.2f})" if p["verdict"] == "inconclusive"
                and detect is not None and math.isfinite(detect) else "")
        lines.append(f"{label if label != last else '':<{scen_w}}{what:<{comp_w}}"
                     f"{interval_text(diff, p['ci95'], 3):<28}{margin_text:<8}"
                     f"{p['verdict']}{note}")
        last = label
    return "\n".join(lines)
