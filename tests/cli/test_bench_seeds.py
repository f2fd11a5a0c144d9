"""`lanekeep bench`'s seed plan (lanekeep/cli/episode.py `bench_seeds`), planned without running an
episode: `--seeds N` alone scores N drawn drives after the file's own seed (the nominal drive,
seen in development, is left out and the summary says how to run it); `--seed S --seeds N`
runs S .. S+N-1; no plan crosses from the scored seeds (0-999) into the tuning seeds (1000+)."""

from __future__ import annotations

import argparse

import pytest

from lanekeep.cli.episode import bench_seeds, seeds_note
from lanekeep.cli.main import main
from lanekeep.core.config_io import ConfigError
from lanekeep.scenario.schema import load_scenario
from lanekeep.tuning.scenarios import SCORED_SEEDS, TUNING_SEEDS_START


def _args(seed: int | None, seeds: int | None) -> argparse.Namespace:
    return argparse.Namespace(seed=seed, seeds=seeds)


def test_seeds_alone_run_the_drawn_drives_after_the_files_seed():
    occlusion = load_scenario("occlusion")  # its file's seed is 12
    assert bench_seeds(_args(None, 3), occlusion) == [13, 14, 15]
    assert bench_seeds(_args(None, 1), occlusion) == [13]
    assert occlusion.seed not in bench_seeds(_args(None, 10), occlusion)
    assert bench_seeds(_args(None, 3), load_scenario("clear_curve")) == [1, 2, 3]
    note = seeds_note(_args(None, 3))
    assert "over 3 seeds each" in note and "nominal drive" in note
    assert "lanekeep run SCENARIO" in note and "without --seeds" in note
    assert "nominal drive" in seeds_note(_args(None, 1))  # one drawn seed is no nominal one


def test_a_chosen_first_seed_runs_from_there():
    occlusion = load_scenario("occlusion")
    assert bench_seeds(_args(5, 3), occlusion) == [5, 6, 7]
    assert bench_seeds(_args(12, 2), occlusion) == [12, 13]  # the user chose the nominal one
    assert seeds_note(_args(5, 3)) == "over 3 seeds each, 5 on"
    tuning = bench_seeds(_args(TUNING_SEEDS_START, 5), occlusion)  # the calibration command
    assert tuning == list(range(1000, 1005))


def test_without_seeds_each_file_runs_its_nominal_seed():
    occlusion = load_scenario("occlusion")
    assert bench_seeds(_args(None, None), occlusion) == [None]  # None: the file's own
    assert bench_seeds(_args(4, None), occlusion) == [4]
    assert seeds_note(_args(None, None)) == "" and seeds_note(_args(4, 1)) == ""


def test_no_plan_crosses_from_scored_into_tuning_seeds():
    occlusion = load_scenario("occlusion")
    last = SCORED_SEEDS.stop - 1 - occlusion.seed  # the most seeds after 12 that stay scored
    assert bench_seeds(_args(None, last), occlusion)[-1] == SCORED_SEEDS.stop - 1
    with pytest.raises(ConfigError, match=r"occlusion's seed 12 \+ 1 run seeds 13-1000"):
        bench_seeds(_args(None, last + 1), occlusion)
    with pytest.raises(ConfigError, match=r"--seed 998 run seeds 998-1002.*tuning"):
        bench_seeds(_args(998, 5), occlusion)


def test_a_crossing_plan_is_one_error_line_before_any_episode(capsys):
    code = main(["bench", "clear_straight", "--seed", "998", "--seeds", "5", "--seconds", "0.1"])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1 and "998-1002" in err[0], err
