"""The regression gate (lanekeep/report/regression.py): a bench against a baseline on the same
seeds fails a scenario only where a metric got worse beyond its margin; a two-mode scenario is
judged by its rate of bad episodes.

No episode runs: bench documents are built by seed_summary.summarise from fake reports and
passed through strict JSON as `bench --json` writes them."""

from __future__ import annotations

import json

import pytest

from lanekeep.report.compare import IncomparableRuns
from lanekeep.report.json_io import dumps
from lanekeep.report.regression import baseline_plan, gate_text, regression_gate
from lanekeep.report.seed_summary import summarise
from lanekeep.scenario.schema import load_scenario
from lanekeep.scoring.metrics import EpisodeReport, SourceReport

SCENARIO = load_scenario("clear_straight")
SEEDS = tuple(range(1, 11))
# Ten drives whose fused RMSE spreads as the bench's do (cm).
BASE = [0.50, 0.62, 0.45, 0.71, 0.55, 0.48, 0.66, 0.52, 0.59, 0.47]
JITTER = [0.004, -0.006, 0.002, 0.005, -0.003, 0.001, -0.004, 0.006, -0.002, 0.003]


def episode(seed: int, rmse: float, car: float = 5.0, departures: int = 0) -> EpisodeReport:
    fused = SourceReport(rmse, 2 * rmse, 1.5 * rmse, 3 * rmse, 1.0, 0.1)
    track = SourceReport(rmse + 0.3, 2 * rmse + 0.3, 1.5 * rmse, 3 * rmse, 1.0, 0.2)
    return EpisodeReport("clear_straight", seed, 1.0, 10,
                         {"fused": fused, "lanenet:track": track}, car, 2 * car, departures,
                         0, 0.0, 0, completed=True, status="completed")


def bench(values: dict[str, list[float]], cars: list[float] | None = None) -> dict:
    cars = cars or [5.0 + 0.1 * i for i in range(len(SEEDS))]
    docs = {label: summarise(label, [episode(s, v, c) for s, v, c in
                                     zip(SEEDS, vs, cars, strict=True)], SCENARIO)
            for label, vs in values.items()}
    return json.loads(dumps(docs))


def test_the_same_loop_passes_and_a_2_cm_bias_fails_naming_the_scenario():
    base = bench({"a": BASE, "b": BASE})
    same = bench({"a": [v + j for v, j in zip(BASE, JITTER, strict=True)], "b": BASE})
    gate = regression_gate(base, same)
    assert gate.passed, gate_text(gate)
    assert gate.comparison["labels"]["a"]["fused.rmse_cm"]["verdict"] == "equivalent"
    biased = bench({"a": BASE, "b": [v + 2.0 + j for v, j in zip(BASE, JITTER, strict=True)]})
    gate = regression_gate(base, biased)
    assert not gate.passed
    assert [(f.label, f.metric) for f in gate.failures] == [("b", "fused.rmse_cm")]
    text = gate_text(gate)
    assert "regression gate: FAIL (1 worse beyond the margin, Holm-adjusted" in text
    assert "b: fused.rmse_cm +2" in text


def test_a_change_within_the_margin_does_not_fail_though_it_is_certain():
    """+0.05 cm on every seed (below the 0.1 cm floor of the RMSE margin) is equivalent: the
    gate is about what matters, not about what is detectable."""
    base = bench({"a": BASE})
    shifted = bench({"a": [v + 0.05 for v in BASE]})
    gate = regression_gate(base, shifted)
    assert gate.passed
    assert gate.comparison["labels"]["a"]["fused.rmse_cm"]["verdict"] in (
        "equivalent", "non-inferior")


def test_the_plan_is_the_baselines_scenarios_and_seeds():
    base = bench({"a": BASE, "b": BASE})
    assert baseline_plan(base) == {"a": list(SEEDS), "b": list(SEEDS)}
    assert baseline_plan(base, ["b"]) == {"b": list(SEEDS)}
    with pytest.raises(IncomparableRuns, match="the baseline has no scenario zz"):
        baseline_plan(base, ["zz"])


def test_a_two_mode_scenario_is_judged_by_its_rate_of_bad_episodes():
    """Occlusion-like: two modes (about 1.7 cm, or 7-12 cm when the markings were hidden).
    A run where the same drives fall in the same modes, values moved within each, passes; a
    run where six more drives fall in the bad mode fails on the rate (McNemar, exact)."""
    good, bad = 1.7, 9.0
    base_modes = [good] * 8 + [bad] * 2
    base = bench({"occ": base_modes})
    jittered = bench({"occ": [v * (1.0 + j) for v, j in zip(base_modes, JITTER, strict=True)]})
    gate = regression_gate(base, jittered, two_mode={"occ": 0.05})
    assert gate.passed and gate.two_mode["occ"]["this_run_bad"] == 2
    worse = bench({"occ": [bad] * 6 + [good] * 2 + [bad] * 2})  # 6 discordant, all one way
    gate = regression_gate(base, worse, two_mode={"occ": 0.05})
    assert not gate.passed
    assert gate.failures[0].metric == "bad episodes (fused RMSE > 5 cm)"
    assert "occ (two-mode): bad episodes (fused RMSE > 5 cm) baseline 2/10, this run 8/10" \
        in gate_text(gate)


def test_a_worse_that_holm_does_not_confirm_is_shown_not_failed():
    """Sixteen scenarios, one of them worse with p about 1% on its own: among sixteen chances
    that is what chance gives, so the gate shows it and passes; the same scenario worse with
    a clear margin fails."""
    labels = [f"s{i}" for i in range(16)]
    big = [10 * v for v in BASE]  # 5-7 cm: the 5% of the margin is above its 0.1 cm floor
    base = bench({label: big for label in labels})
    # s0: +11% on average against a 5% margin, spread so that its own p_worse is ~1%
    nudged = [v * (1.11 + j * 16) for v, j in zip(big, JITTER, strict=True)]
    gate = regression_gate(base, bench({**{label: big for label in labels}, "s0": nudged}))
    entry = gate.comparison["labels"]["s0"]["fused.rmse_cm"]
    assert entry["verdict"] == "worse" and 0.025 / 16 < entry["p_worse"] < 0.025, entry
    assert gate.passed and [f.label for f in gate.unconfirmed] == ["s0"]
    assert "worse on their own, not after Holm" in gate_text(gate)
    clear = [v * (1.5 + j) for v, j in zip(big, JITTER, strict=True)]
    gate = regression_gate(base, bench({**{label: big for label in labels}, "s0": clear}))
    assert not gate.passed and [f.label for f in gate.failures] == ["s0"]


def test_drives_that_newly_end_in_a_collision_fail_the_gate_though_none_departed():
    """Eight of ten drives now end in a collision before they leave the lane: the departures
    see nothing (McNemar has no discordant pair), `failed` sees 8 discordant pairs one way."""
    base = bench({"a": BASE})
    crashed = bench({"a": BASE})
    for e in crashed["a"]["episodes"][:8]:
        e.update(status="collision", completed=False, stop_reason="collision")
    gate = regression_gate(base, crashed)
    assert [(f.label, f.metric) for f in gate.failures] == [("a", "failed")]
    assert gate.comparison["labels"]["a"]["lane_departures"]["verdict"] == "inconclusive"
