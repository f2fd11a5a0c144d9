"""Two bench runs paired per scenario and seed (lanekeep/report/compare.py): B - A with its
paired 95% interval (on the log scale for errors) and the verdict for B against the metric's
margin, the stratified "all" row, Holm-adjusted counts, --margin overrides, refusals when the
runs cannot be paired.

No episode runs: the bench documents are built by seed_summary.summarise from small fake
EpisodeReports, then passed through strict JSON as `bench --json` writes them."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from scipy import stats as sps

from lanekeep.report.compare import (
    DEFAULT_METRICS,
    WIDTH,
    IncomparableRuns,
    cell_text,
    claim_counts,
    compare_document,
    compare_runs,
    compare_table,
    margin_of,
    metric_set,
    parse_margins,
    parse_metric,
)
from lanekeep.report.json_io import SCHEMA_VERSION, dumps, report_document
from lanekeep.report.seed_summary import summarise
from lanekeep.scenario.schema import load_scenario
from lanekeep.scoring import statistics as stats
from lanekeep.scoring.metrics import EpisodeReport, SourceReport

SCENARIO = load_scenario("clear_straight")
SEEDS = (0, 1, 2, 3, 4)
NAN = math.nan


def episode(seed: int, rmse: float, car: float = 5.0, departures: int = 0,
            valid: float = 1.0, status: str = "completed") -> EpisodeReport:
    """A fake episode: fused RMSE `rmse` (max, ADE, FDE derived from it), a track source."""
    fused = SourceReport(rmse, 2 * rmse, 1.5 * rmse, 3 * rmse, valid, 0.1)
    track = SourceReport(rmse + 1.0, 2 * rmse + 1.0, 1.5 * rmse, 3 * rmse, 0.9, 0.2)
    return EpisodeReport("clear_straight", seed, 1.0, 10, {"fused": fused, "hough:track": track},
                         car, 2 * car, departures, 0, 0.0, 0,
                         completed=status == "completed", status=status)


def bench(runs: dict[str, list[EpisodeReport]], controller: str | None = None) -> dict:
    """A bench --json document as read back from its file."""
    overrides = {"front_detectors": None, "reference_detector": None,
                 "controller": controller, "settings": [], "weights": None}
    docs = {label: summarise(label, reports, SCENARIO, overrides=overrides)
            for label, reports in runs.items()}
    return json.loads(dumps(docs))


def rmse_run(values: dict[str, list[float]], **kw) -> dict:
    """Labels whose seeds SEEDS have these fused RMSEs."""
    return bench({label: [episode(s, v) for s, v in zip(SEEDS, vs, strict=True)]
                  for label, vs in values.items()}, **kw)


# Seeds differ a lot (the drive), B is 20% lower on every one: only pairing sees it. (It was
# 0.1 cm lower: inside the RMSE's margin, max(0.1 cm, 5%), that is no longer a claim.)
A_VALUES = [1.0, 3.0, 5.0, 2.0, 4.0]
B_LOWER = [0.8 * v * (1 + d) for v, d in zip(A_VALUES, [0.01, -0.01, 0.0, 0.02, -0.02],
                                             strict=True)]
KEY = "fused.rmse_cm"


def test_b_lower_on_every_seed_is_better_though_the_seeds_spread_far_more():
    result = compare_runs(rmse_run({"x": A_VALUES}), rmse_run({"x": B_LOWER}))
    entry = result["labels"]["x"][KEY]
    logs = np.log(B_LOWER) - np.log(A_VALUES)
    assert entry["verdict"] == "better" and entry["n"] == 5
    # errors on the log scale: the ratio B / A per seed, its geometric mean and t interval
    assert entry["ratio"] == pytest.approx(math.exp(logs.mean()))
    lo, hi = sps.t.interval(0.95, 4, loc=logs.mean(), scale=sps.sem(logs))
    assert entry["ratio_ci95"] == pytest.approx([math.exp(lo), math.exp(hi)])
    # given back in cm: A's geometric mean x (ratio - 1) = gmean(B) - gmean(A)
    assert entry["diff"] == pytest.approx(sps.gmean(B_LOWER) - sps.gmean(A_VALUES))
    assert entry["ci95"] == pytest.approx([sps.gmean(A_VALUES) * math.expm1(lo),
                                           sps.gmean(A_VALUES) * math.expm1(hi)])
    assert entry["a_mean"] == pytest.approx(np.mean(A_VALUES))
    assert entry["b_mean"] == pytest.approx(np.mean(B_LOWER))
    assert entry["margin"] == pytest.approx(max(0.1, 0.05 * sps.gmean(A_VALUES)))
    lo, hi = entry["ci95"]
    assert lo < entry["diff"] < hi < -entry["margin"]
    # unpaired, the two runs' 95% intervals overlap almost entirely
    spread_a = stats.spread(A_VALUES, log_scale=True).ci95
    spread_b = stats.spread(B_LOWER, log_scale=True).ci95
    assert spread_b[1] > spread_a[0] and np.std(A_VALUES) > 2 * abs(entry["diff"])


def test_b_higher_is_worse_and_the_verdict_is_about_b():
    result = compare_runs(rmse_run({"x": B_LOWER}), rmse_run({"x": A_VALUES}))
    entry = result["labels"]["x"][KEY]
    assert entry["verdict"] == "worse" and entry["diff"] > entry["margin"]
    assert entry["p_worse"] < stats.ALPHA_ONE_SIDED < entry["p_better"]


def test_valid_share_is_higher_better():
    a = bench({"x": [episode(s, 1.0, valid=0.8 + 0.01 * s) for s in SEEDS]})
    b = bench({"x": [episode(s, 1.0, valid=0.9 + 0.01 * s + 0.001 * (s % 2)) for s in SEEDS]})
    entry = compare_runs(a, b)["labels"]["x"]["fused.valid_share"]
    assert entry["diff"] > 0 and entry["verdict"] == "better"
    # a share is no error: plain differences, the mean's t interval, no ratio
    assert "ratio" not in entry
    assert entry["diff"] == pytest.approx(entry["b_mean"] - entry["a_mean"])
    assert entry["margin"] == pytest.approx(0.02)


def test_noise_either_way_is_inconclusive_with_what_this_n_detects():
    noisy = [v + d for v, d in zip(A_VALUES, [0.5, -0.6, 0.4, -0.3, 0.1], strict=True)]
    entry = compare_runs(rmse_run({"x": A_VALUES}), rmse_run({"x": noisy})
                         )["labels"]["x"][KEY]
    assert entry["verdict"] == "inconclusive"
    assert entry["ci95"][0] < -entry["margin"] < 0.0 < entry["margin"] < entry["ci95"][1]
    assert entry["detectable"] > entry["margin"]


def test_identical_runs_are_equivalent_with_a_zero_difference():
    run = rmse_run({"x": A_VALUES})
    result = compare_runs(run, run)
    for key in result["better_when"]:
        entry = result["labels"]["x"][key]
        if stats.is_exact(key):  # McNemar: no discordant seed, no claim either way
            assert entry["diff"] == 0.0 and entry["verdict"] == "inconclusive"
            assert entry["p_worse"] == entry["p_better"] == 1.0
            continue
        assert entry["diff"] == 0.0 and entry["verdict"] == "equivalent", key


def test_a_rounding_difference_on_every_seed_is_equivalent_not_worse():
    """Issue case 2: 1e-15 cm more on every seed (another kernel) is no regression."""
    result = compare_runs(rmse_run({"x": A_VALUES}),
                          rmse_run({"x": [v + 1e-15 for v in A_VALUES]}))
    assert result["labels"]["x"][KEY]["verdict"] == "equivalent"


def test_two_seeds_give_no_verdict():
    """Issue case 2: n < 3 pairs, however one-sided: too few."""
    a = bench({"x": [episode(s, 1.0) for s in (0, 1)]})
    b = bench({"x": [episode(s, 0.1) for s in (0, 1)]})
    result = compare_runs(a, b)
    assert {e["verdict"] for e in result["labels"]["x"].values()} == {"too few"}
    assert any("fewer than 3 seeds per label: no verdict" in n for n in result["notes"])


def _labels(n_noisy: int = 1) -> tuple[dict, dict]:
    """Issue case 4: one label swinging by 47 cm sd, nine each 20% worse (A, B)."""
    noisy_a = [150.0, 200.0, 100.0, 250.0, 180.0]
    swings = [60.0, -50.0, 40.0, -30.0, -20.0]
    a = {"occlusion": noisy_a}
    b = {"occlusion": [x + s for x, s in zip(noisy_a, swings, strict=True)]}
    jitter = [0.01, -0.02, 0.0, 0.015, -0.005]
    for i in range(9):
        values = [(2.0 + 0.3 * i) * f for f in (1.0, 1.3, 0.8, 1.1, 0.9)]
        a[f"s{i}"] = values
        b[f"s{i}"] = [x * 1.2 * (1 + jitter[(i + j) % 5]) for j, x in enumerate(values)]
    return a, b


def test_the_stratified_all_row_is_not_swamped_by_one_noisy_label():
    """Issue case 4: the "all" row weighs each label once on the ratio scale: "worse". The old
    row concatenated every raw pair and drowned in the noisy label's spread."""
    a, b = _labels()
    assert np.std(np.subtract(b["occlusion"], a["occlusion"]), ddof=1) == pytest.approx(
        47.4, abs=0.1)
    result = compare_runs(rmse_run(a), rmse_run(b), [KEY])
    pooled = result["all"][KEY]
    assert pooled["verdict"] == "worse" and pooled["scale"] == "ratio"
    assert pooled["labels"] == 10 and pooled["labels_up"] == 10
    assert 1.1 < pooled["ci95"][0] < pooled["diff"] < pooled["ci95"][1]
    concat_a = [x for v in a.values() for x in v]
    concat_b = [x for v in b.values() for x in v]
    old = stats.paired(concat_b, concat_a, margin=stats.margin_for(KEY))
    assert old.verdict == "inconclusive"  # what the raw pairs, concatenated, would say
    counts = result["counts"][KEY]
    assert counts["worse"] == 9 and counts["inconclusive"] == 1 and counts["better"] == 0
    assert result["labels"]["occlusion"][KEY]["verdict"] == "inconclusive"
    assert counts["expected_by_chance"] == pytest.approx(0.025 * 10)
    entries = [e[KEY] for e in result["labels"].values()]
    assert counts["worse_holm"] == _holm_count(entries, "worse") == 9
    row = next(line for line in compare_table(result).splitlines()
               if line.startswith("all (stratified) "))
    assert row.split()[-1] == "w"


def test_all_weighs_each_label_once():
    """The "all" row: each label's mean log ratio, averaged with equal weight (a label with
    fewer seeds counts as much), Welch-Satterthwaite degrees of freedom, a sign test."""
    a_docs = {"x": [episode(s, v) for s, v in zip(SEEDS, A_VALUES, strict=True)],
              "y": [episode(s, 10 * v) for s, v in zip(SEEDS, A_VALUES, strict=True)],
              "z": [episode(s, v) for s, v in zip(SEEDS[:3], A_VALUES[:3], strict=True)]}
    y_b = [10 * v + d for v, d in zip(A_VALUES, [3, -3, 2, -2, 0], strict=True)]
    z_b = [v * 0.7 for v in A_VALUES[:3]]
    b_docs = {"x": [episode(s, v) for s, v in zip(SEEDS, B_LOWER, strict=True)],
              "y": [episode(s, v) for s, v in zip(SEEDS, y_b, strict=True)],
              "z": [episode(s, v) for s, v in zip(SEEDS[:3], z_b, strict=True)]}
    result = compare_runs(bench(a_docs), bench(b_docs))
    pooled = result["all"][KEY]
    per_label = [np.log(B_LOWER) - np.log(A_VALUES),
                 np.log(y_b) - np.log([10 * v for v in A_VALUES]),
                 np.log(z_b) - np.log(A_VALUES[:3])]
    means = [d.mean() for d in per_label]
    variances = [d.var(ddof=1) / len(d) for d in per_label]
    var = sum(variances) / 9
    df = var**2 / sum((v / 9) ** 2 / (len(d) - 1)
                      for v, d in zip(variances, per_label, strict=True))
    half = sps.t.ppf(0.975, df) * math.sqrt(var)
    assert pooled["labels"] == 3 and pooled["scale"] == "ratio"
    assert pooled["diff"] == pytest.approx(math.exp(np.mean(means)))
    assert pooled["diff"] != pytest.approx(math.exp(np.concatenate(per_label).mean()))
    assert pooled["df"] == pytest.approx(df)
    assert pooled["ci95"] == pytest.approx([math.exp(np.mean(means) - half),
                                           math.exp(np.mean(means) + half)])
    # the verdict: that interval against the labels' mean margin (each a log ratio)
    margins = [math.log1p(max(0.1, 0.05 * sps.gmean(a)) / sps.gmean(a))
               for a in (A_VALUES, [10 * v for v in A_VALUES], A_VALUES[:3])]
    assert pooled["margin"] == pytest.approx(math.exp(np.mean(margins)))
    assert pooled["verdict"] == stats.classify(np.mean(means) - half, np.mean(means) + half,
                                               np.mean(margins))
    assert pooled["labels_down"] == 2 and pooled["labels_up"] == 1  # y's noise leans up
    assert pooled["sign_test_p"] == pytest.approx(sps.binomtest(1, 3, 0.5).pvalue)
    labels = result["labels"]
    assert labels["y"][KEY]["verdict"] == "inconclusive"
    assert labels["x"][KEY]["verdict"] == labels["z"][KEY]["verdict"] == "better"
    counts = result["counts"][KEY]
    assert {k: counts[k] for k in stats.VERDICTS} == {
        "better": 2, "worse": 0, "equivalent": 0, "non-inferior": 0, "non-superior": 0,
        "inconclusive": 1, "too few": 0}
    assert set(result["counts"]) == {m.key for m in DEFAULT_METRICS}
    # two labels: no stratified verdict (too few labels to pool), the row still shows the ratio
    two = compare_runs(rmse_run({"x": A_VALUES, "y": A_VALUES}),
                       rmse_run({"x": B_LOWER, "y": B_LOWER}))
    assert two["all"][KEY]["verdict"] == "too few"


def test_departures_are_pooled_over_every_label_and_seed_exactly():
    """McNemar per label (too few discordant seeds for a claim), and over every (label, seed)
    pair in the "all" row: six discordant pairs one way are a claim (2^-6 < 2.5%)."""
    a = bench({lab: [episode(s, 1.0) for s in SEEDS] for lab in ("p", "q", "r")})
    b = bench({lab: [episode(s, 1.0, departures=int(s < 2)) for s in SEEDS]
               for lab in ("p", "q", "r")})
    result = compare_runs(a, b, ["lane_departures"])
    for label in ("p", "q", "r"):
        entry = result["labels"][label]["lane_departures"]
        assert entry["verdict"] == "inconclusive" and entry["diff"] == pytest.approx(0.4)
        assert entry["p_worse"] == pytest.approx(sps.binomtest(2, 2, 0.5,
                                                               alternative="greater").pvalue)
    pooled = result["all"]["lane_departures"]
    assert pooled["scale"] == "rate" and pooled["n"] == 15 and pooled["labels"] == 3
    assert pooled["verdict"] == "worse" and pooled["diff"] == pytest.approx(0.4)
    assert pooled["p_worse"] == pytest.approx(0.5 ** 6)


def test_a_drive_a_collision_ended_fails_though_it_never_departed():
    """Departures alone pair A's crash (no departure: the collision ended it first) with B's
    departure as "A better"; `failed` counts both, so the pair is concordant. Off-road and
    unstable ends fail too; an interrupted run does not (the car did not fail)."""
    ends = ["collision", "off_road", "unstable", "interrupted", "completed"]
    a = bench({"x": [episode(s, 1.0, status=end) for s, end in zip(SEEDS, ends, strict=True)]})
    b = bench({"x": [episode(s, 1.0, departures=int(s == 0)) for s in SEEDS]})
    result = compare_runs(a, b, ["lane_departures", "failed"])
    departures, failed = (result["labels"]["x"][k] for k in ("lane_departures", "failed"))
    assert (departures["a_mean"], departures["b_mean"]) == (0.0, 0.2)
    assert (failed["a_mean"], failed["b_mean"]) == (pytest.approx(0.6), 0.2)
    assert failed["diff"] == pytest.approx(-0.4)  # seeds 1, 2 failed in A only; 0 in both
    assert a["x"]["failed_episodes"] == 3 and b["x"]["failed_episodes"] == 1
    assert a["x"]["failure_rate_ci95"] == list(stats.rate_interval(3, 5))


def _holm_count(entries: list[dict], claim: str) -> int:
    """Holm's step-down by hand: the i-th smallest of m finite p-values (0-based) is rejected
    while p < alpha / (m - i); a claim counts when rejected and its verdict says it."""
    ps = [e.get(f"p_{claim}") for e in entries]
    finite = sorted((p, i) for i, p in enumerate(ps) if p is not None and math.isfinite(p))
    rejected = set()
    for rank, (p, i) in enumerate(finite):
        if p >= stats.ALPHA_ONE_SIDED / (len(finite) - rank):
            break
        rejected.add(i)
    return sum(1 for i in rejected if entries[i]["verdict"] == claim)


def test_claim_counts_adjust_better_and_worse_by_holm():
    """Issue case 5: Holm's counts never exceed the raw counts, and are what Holm gives."""
    entries = [
        {"verdict": "worse", "p_worse": 0.001, "p_better": 0.999},
        {"verdict": "worse", "p_worse": 0.006, "p_better": 0.994},
        {"verdict": "worse", "p_worse": 0.02, "p_better": 0.98},
        {"verdict": "better", "p_worse": 0.9, "p_better": 0.002},
        {"verdict": "better", "p_worse": 0.95, "p_better": 0.015},
        {"verdict": "inconclusive", "p_worse": 0.3, "p_better": 0.4},
        {"verdict": "equivalent", "p_worse": 0.8, "p_better": 0.7},
        {"verdict": "too few", "p_worse": None, "p_better": None},  # JSON null: not in m
    ]
    counts = claim_counts(entries)
    assert counts["worse"] == 3 and counts["better"] == 2 and counts["too few"] == 1
    # m = 7: worse 0.001 * 7 < 2.5%, then 0.006 * 6 = 3.6% stops; better 0.002 * 7 = 1.4%,
    # then 0.015 * 6 = 9% stops
    assert counts["worse_holm"] == 1 == _holm_count(entries, "worse")
    assert counts["better_holm"] == 1 == _holm_count(entries, "better")
    assert counts["worse_holm"] <= counts["worse"] and counts["better_holm"] <= counts["better"]
    assert counts["expected_by_chance"] == pytest.approx(0.025 * len(entries))
    # alone, each raw claim survives: Holm over one test is the test itself
    assert claim_counts(entries[2:3])["worse_holm"] == 1


def test_holm_counts_over_real_labels_match_a_hand_computation():
    a, b = _labels()
    result = compare_runs(rmse_run(b), rmse_run(a))  # the other way round: nine better
    for key, counts in result["counts"].items():
        for claim in ("better", "worse"):
            entries = [e[key] for e in result["labels"].values()]
            assert counts[f"{claim}_holm"] == _holm_count(entries, claim)
            assert counts[f"{claim}_holm"] <= counts[claim]
    assert result["counts"][KEY]["better"] == 9


def test_a_seed_without_a_value_in_either_run_is_left_out_of_the_pairs():
    a = rmse_run({"x": A_VALUES})
    b = rmse_run({"x": [B_LOWER[0], NAN, *B_LOWER[2:]]})
    assert b["x"]["episodes"][1]["sources"]["fused"]["rmse_cm"] is None  # strict JSON: null
    entry = compare_runs(a, b)["labels"]["x"]["fused.rmse_cm"]
    kept = [0, 2, 3, 4]
    assert entry["n"] == 4 and entry["dropped"] == 1
    assert entry["a_mean"] == pytest.approx(np.mean([A_VALUES[i] for i in kept]))
    # on the log scale diff = gmean(B) - gmean(A), over the kept pairs only
    assert entry["diff"] == pytest.approx(sps.gmean([B_LOWER[i] for i in kept])
                                          - sps.gmean([A_VALUES[i] for i in kept]))


def test_default_metrics_and_their_direction():
    result = compare_runs(rmse_run({"x": A_VALUES}), rmse_run({"x": B_LOWER}))
    assert result["better_when"] == {
        "fused.rmse_cm": "lower", "fused.max_cm": "lower", "fused.ade_cm": "lower",
        "fused.fde_cm": "lower", "fused.valid_share": "higher", "car_rms_cm": "lower",
        "car_max_cm": "lower", "lane_departures": "lower", "failed": "lower"}
    entry = result["labels"]["x"]["lane_departures"]
    assert set(entry) == {"a_mean", "b_mean", "diff", "ci95", "verdict", "n", "margin",
                          "p_worse", "p_better", "detectable", "dropped"}
    assert set(result["labels"]["x"][KEY]) == set(entry) | {"ratio", "ratio_ci95"}
    assert result["margins"] == {
        "fused.rmse_cm": "max(0.1, 5%)", "fused.max_cm": "max(0.5, 5%)",
        "fused.ade_cm": "max(0.1, 5%)", "fused.fde_cm": "max(0.2, 5%)",
        "fused.valid_share": "0.02", "car_rms_cm": "max(0.2, 5%)",
        "car_max_cm": "max(0.5, 5%)", "lane_departures": "0", "failed": "0"}


def test_metric_keys_parse_and_other_sources_add_their_metrics():
    assert parse_metric("hough:track.drift_cm").source == "hough:track"
    assert parse_metric("car_rms_cm").source is None
    assert parse_metric("fused.valid_share").lower_is_better is False
    with pytest.raises(ValueError, match="unknown metric 'fused.speed'"):
        parse_metric("fused.speed")
    keys = [m.key for m in metric_set(["car_rms_cm"], ["hough:track"])]
    assert keys == ["car_rms_cm", "hough:track.rmse_cm", "hough:track.max_cm",
                    "hough:track.ade_cm", "hough:track.fde_cm", "hough:track.valid_share"]
    result = compare_runs(rmse_run({"x": A_VALUES}), rmse_run({"x": B_LOWER}),
                          metric_set(sources=["hough:track"]))
    assert result["labels"]["x"]["hough:track.rmse_cm"]["verdict"] == "better"


def test_a_source_missing_in_a_run_is_named():
    a, b = rmse_run({"x": A_VALUES}), rmse_run({"x": B_LOWER})
    with pytest.raises(IncomparableRuns, match="source 'lanenet:track' is not in A"):
        compare_runs(a, b, ["lanenet:track.rmse_cm"])
    del b["x"]["episodes"][2]["sources"]["hough:track"]
    with pytest.raises(IncomparableRuns, match=r"source 'hough:track' is not in B \(x seed 2 "
                                               r"has fused\)"):
        compare_runs(a, b, ["hough:track.rmse_cm"])


def test_other_labels_are_refused_naming_them():
    with pytest.raises(IncomparableRuns, match=r"different labels \(only in B: y\)"):
        compare_runs(rmse_run({"x": A_VALUES}), rmse_run({"x": B_LOWER, "y": B_LOWER}))


def test_other_seeds_are_refused_naming_the_label():
    a = rmse_run({"x": A_VALUES})
    b = bench({"x": [episode(s + 10, v) for s, v in zip(SEEDS, B_LOWER, strict=True)]})
    with pytest.raises(IncomparableRuns, match=r"x: the runs have different seeds \(A: 0..4; "
                                               r"B: 10..14\)"):
        compare_runs(a, b)


@pytest.mark.parametrize("document", [
    json.loads(dumps(report_document(episode(0, 1.0), SCENARIO))),  # a `run --json` file
    {"clear_straight": {"schema_version": 1, "scenario": "clear_straight",
                        "sources": {"fused": {"rmse_cm": 1.0}}}},  # an old bench file
    [1, 2], {},
])
def test_a_document_that_is_no_bench_document_is_refused(document):
    with pytest.raises(IncomparableRuns) as err:
        compare_runs(rmse_run({"x": A_VALUES}), document)
    assert f"B: not a bench --json document (schema_version {SCHEMA_VERSION})" in str(err.value)
    assert "\n" not in str(err.value)


def test_another_scenario_file_is_a_note_not_a_refusal():
    a, b = rmse_run({"x": A_VALUES}), rmse_run({"x": B_LOWER})
    b["x"]["scenario_sha256"] = "0" * 64
    result = compare_runs(a, b)
    assert result["labels"]["x"]["fused.rmse_cm"]["verdict"] == "better"
    assert any(n.startswith("scenario file differs: x") for n in result["notes"])
    assert not compare_runs(a, a)["notes"]


def test_an_episode_that_did_not_complete_is_noted():
    a = rmse_run({"x": A_VALUES})
    b = bench({"x": [episode(s, v, status="unstable" if s == 3 else "completed")
                     for s, v in zip(SEEDS, B_LOWER, strict=True)]})
    assert any("B: x seed 3 did not complete (unstable)" in n
               for n in compare_runs(a, b)["notes"])


def test_one_seed_gives_no_interval_and_says_so():
    a = bench({"x": [episode(0, 1.0)]})
    b = bench({"x": [episode(0, 0.5)]})
    result = compare_runs(a, b)
    entry = result["labels"]["x"]["fused.rmse_cm"]
    assert entry["diff"] == pytest.approx(-0.5) and entry["verdict"] == "too few"
    assert all(math.isnan(c) for c in entry["ci95"])
    assert any("fewer than 3 seeds per label: no verdict" in n for n in result["notes"])
    assert "-0.50 -" in compare_table(result)


def test_the_table_names_the_runs_what_differs_and_fits_120_columns():
    a = rmse_run({"clear_straight": A_VALUES, "a_rather_long_label@lanenet": A_VALUES})
    b = rmse_run({"clear_straight": B_LOWER, "a_rather_long_label@lanenet": A_VALUES},
                 controller="stanley")
    result = compare_runs(a, b, metric_set(sources=["hough:track"]),
                          a_name="before.json", b_name="after.json")
    text = compare_table(result)
    lines = text.splitlines()
    assert max(len(line) for line in lines) <= WIDTH
    assert "A = before.json" in text and "B = after.json" in text
    assert "controller: (scenario file's) -> stanley" in text
    assert "better = B lower (higher for valid_share)" in text
    row = next(line for line in lines if line.startswith("clear_straight"))
    diff = result["labels"]["clear_straight"][KEY]["diff"]  # gmean(B) - gmean(A), cm
    assert row.split()[1] == f"{diff:+.2f}" == "-0.52"
    assert row.split()[4] == "b"  # fused RMSE, the verdict's letter
    all_row = next(line for line in lines if line.startswith("all (stratified) "))
    ratio = result["all"][KEY]["diff"]
    assert all_row.split()[2] == f"{100 * (ratio - 1):+.1f}%"  # B / A over labels
    assert all_row.split()[5] == "-"  # two labels: too few to pool
    assert "fused.rmse_cm 1b 0w 1e (Holm: 1b 0w)" in text  # the long label: A against A
    assert "fused.rmse_cm max(0.1, 5%)" in text  # the margins in force
    assert stats.LEGEND in " ".join(text.split())  # wrapped within WIDTH
    assert "hough:track.rmse_cm" in text


@pytest.mark.parametrize("verdict", stats.VERDICTS)
def test_cells_end_with_the_verdicts_letter(verdict):
    entry = {"diff": -0.123, "ci95": [-0.2, -0.05], "verdict": verdict}
    assert cell_text(entry, KEY) == f"-0.12 [-0.20, -0.05] {stats.LETTERS[verdict]}"
    ratio = {"diff": 1.031, "ci95": [0.99, 1.073], "verdict": verdict, "scale": "ratio"}
    assert cell_text(ratio, KEY) == f"+3.1% [-1.0, +7.3] {stats.LETTERS[verdict]}"
    assert cell_text({"diff": None, "ci95": [None, None], "verdict": verdict}, KEY) == "-"


def test_margins_parse_with_a_label_or_a_share():
    """Issue case 6: --margin [LABEL:]METRIC=ABS[,REL%]."""
    margins = parse_margins(["fused.rmse_cm=0.2,5%", "occlusion:car_max_cm=1",
                             "hough:track.rmse_cm=0.3", "occlusion:hough:track.max_cm=2,10"])
    assert margins == {"fused.rmse_cm": stats.Margin(0.2, 0.05),
                       "occlusion:car_max_cm": stats.Margin(1.0),
                       "hough:track.rmse_cm": stats.Margin(0.3),
                       "occlusion:hough:track.max_cm": stats.Margin(2.0, 0.1)}
    rmse, car_max = parse_metric(KEY), parse_metric("car_max_cm")
    track_max = parse_metric("hough:track.max_cm")
    assert margin_of(rmse, "x", margins) == stats.Margin(0.2, 0.05)  # every label
    assert margin_of(car_max, "occlusion", margins) == stats.Margin(1.0)  # this label only
    assert margin_of(car_max, "x", margins) == stats.MARGINS["car_max_cm"]  # the declared
    assert margin_of(car_max, None, margins) == stats.MARGINS["car_max_cm"]
    assert margin_of(parse_metric("hough:track.rmse_cm"), "x", margins) == stats.Margin(0.3)
    assert margin_of(track_max, "occlusion", margins) == stats.Margin(2.0, 0.1)
    assert margin_of(track_max, "x", margins) == stats.MARGINS["max_cm"]
    assert margin_of(rmse, "x", None) == stats.MARGINS["rmse_cm"]
    assert parse_margins([]) == {}


@pytest.mark.parametrize("text", [
    "fused.rmse_cm", "fused.rmse_cm=", "=0.2", "fused.speed=1", "occlusion:=1",
    "fused.rmse_cm=-1", "fused.rmse_cm=abc", "fused.rmse_cm=0.2,-5%", "fused.rmse_cm=1,2,3",
    "fused.rmse_cm=nan", "fused.rmse_cm=0.2,nan%",
])
def test_a_bad_margin_raises_naming_the_text(text):
    with pytest.raises(ValueError) as err:
        parse_margins(["car_rms_cm=1", text])
    assert repr(text) in str(err.value) and "\n" not in str(err.value)
    assert "[LABEL:]METRIC=ABS[,REL%]" in str(err.value)


def test_a_margin_override_applies_where_it_is_given():
    """Issue case 6: a label's override changes that label's verdict only; a metric's changes
    every label's, the "all" row's and the margin reported."""
    a = rmse_run({"x": A_VALUES, "y": A_VALUES, "z": A_VALUES})
    b = rmse_run({"x": B_LOWER, "y": B_LOWER, "z": B_LOWER})
    plain = compare_runs(a, b, [KEY])
    assert {e[KEY]["verdict"] for e in plain["labels"].values()} == {"better"}
    assert plain["all"][KEY]["verdict"] == "better"
    huge = stats.Margin(5.0)
    one = compare_runs(a, b, [KEY], margins={f"x:{KEY}": huge})
    assert one["labels"]["x"][KEY]["verdict"] == "equivalent"
    assert one["labels"]["x"][KEY]["margin"] == 5.0
    assert one["labels"]["y"][KEY] == plain["labels"]["y"][KEY]
    assert one["all"][KEY] == plain["all"][KEY] and one["margins"] == plain["margins"]
    every = compare_runs(a, b, [KEY], margins={KEY: huge})
    assert {e[KEY]["verdict"] for e in every["labels"].values()} == {"equivalent"}
    assert every["all"][KEY]["verdict"] == "equivalent" and every["margins"][KEY] == "5"
    # a margin for a metric not compared changes nothing
    assert compare_runs(a, b, [KEY], margins={"car_rms_cm": huge})["labels"] == plain["labels"]


def test_the_document_is_strict_json_with_a_schema_version():
    a = bench({"x": [episode(0, 1.0)]})
    doc = compare_document(compare_runs(a, a))
    assert doc["schema_version"] == SCHEMA_VERSION and "lanekeep_version" in doc
    back = json.loads(dumps(doc), parse_constant=lambda t: pytest.fail(f"not strict: {t}"))
    assert back["labels"]["x"]["fused.rmse_cm"]["ci95"] == [None, None]
