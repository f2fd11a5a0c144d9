"""lanekeep/loop/bench_plan.py (`lanekeep bench`'s plan, without running an episode): a job
per scenario and seed in the order named, model-only loops after the main ones, labels that
carry the seed only when a scenario runs on several, and every scenario checked on every seed
before anything runs."""

from __future__ import annotations

import dataclasses

import pytest

from lanekeep.core.config_io import ConfigError
from lanekeep.loop import bench_plan as bp
from lanekeep.loop.overrides import PluginOverrides
from lanekeep.scenario.schema import ScenarioError, load_scenario

NAMES = ["clear_curve", "occlusion"]


@pytest.fixture(scope="module")
def scenarios():
    return bp.bench_scenarios(NAMES, None, PluginOverrides())


def test_one_seed_each_labels_by_scenario(scenarios):
    plan = bp.plan_jobs(NAMES, scenarios, {n: [None] for n in NAMES}, None, PluginOverrides(),
                        single_model=False)
    assert not plan.many and plan.jobs == plan.main_jobs
    assert plan.main_labels == NAMES


def test_several_seeds_label_each_episode_and_model_only_loops_come_last(scenarios):
    seeds = {"clear_curve": [1, 2], "occlusion": [13]}
    plan = bp.plan_jobs(NAMES, scenarios, seeds, "paper", PluginOverrides(), single_model=True)
    assert plan.many
    assert plan.main_labels == ["clear_curve.seed1", "clear_curve.seed2", "occlusion.seed13"]
    models = [(j.label, j.seed) for j in plan.jobs[len(plan.main_jobs):]]
    expected = [(f"{name}@{model}", seed) for name in NAMES
                for model in scenarios[name].estimation.front_detectors for seed in seeds[name]]
    assert models == expected and all(j.mode == "paper" for j in plan.jobs)
    documents = {label: {"label": label} for label in {j.label for j in plan.jobs}}
    assert [d["label"] for d in bp.main_documents(plan, documents)] == NAMES


def test_the_progress_bar_has_a_period_only_when_all_share_one(scenarios):
    assert bp.control_period_s(scenarios) == scenarios["clear_curve"].control_period_s
    slower = dataclasses.replace(scenarios["occlusion"], control_period_s=0.2)
    assert bp.control_period_s({**scenarios, "occlusion": slower}) is None


def test_every_scenario_is_checked_on_every_seed_before_anything_runs(scenarios):
    bp.check_bench(scenarios, {n: [None, 3] for n in NAMES}, seconds=1.0)
    with pytest.raises(ConfigError, match="--seconds: .* less than one control step"):
        bp.check_bench(scenarios, {n: [None] for n in NAMES}, seconds=0.01)


def test_a_bad_scenario_name_fails_at_planning():
    with pytest.raises(ScenarioError, match="unknown scenario 'no_such_scenario'"):
        bp.bench_scenarios(["clear_curve", "no_such_scenario"], None, PluginOverrides())


def test_the_mode_comes_before_the_command_lines_detectors():
    paper = bp.bench_scenarios(["clear_curve"], "paper", PluginOverrides())["clear_curve"]
    assert paper == load_scenario_in_mode("clear_curve", "paper")


def load_scenario_in_mode(name: str, mode: str):
    from lanekeep.loop.paper_mode import with_mode

    return with_mode(load_scenario(name), mode)
