"""The thin CLI: scenarios listing, render snapshots, clear errors with exit code 2."""

from lanekeep.cli.main import main
from lanekeep.scenario.schema import shipped_scenarios


def test_scenarios_lists_each_with_a_description(capsys):
    assert main(["scenarios"]) == 0
    lines = capsys.readouterr().out.strip().splitlines()
    assert [line.split()[0] for line in lines] == shipped_scenarios()
    assert all(len(line.split(maxsplit=1)[1]) > 20 for line in lines)


def test_render_writes_four_pngs(tmp_path, capsys):
    import cv2

    assert main(["render", "clear_straight", "--at", "30", "--out", str(tmp_path)]) == 0
    names = sorted(p.name for p in tmp_path.iterdir())
    assert names == ["front.png", "front_seg.png", "rear.png", "rear_seg.png"]
    front = cv2.imread(str(tmp_path / "front.png"))
    assert front.shape == (720, 1280, 3)
    assert front[600:, :, :].std() > 5  # textured road, not a flat fill


def test_render_applies_the_scenarios_image_effects_unless_told_not_to(tmp_path, capsys):
    """heavy_rain's snapshot is the episode's first frame (streaks, drops, mist), not the sunny
    render underneath it; --no-effects gives that bare render."""
    import cv2
    import numpy as np

    from lanekeep.loop.episode import Episode
    from lanekeep.scenario.schema import load_scenario

    wet, dry = tmp_path / "effects", tmp_path / "bare"
    assert main(["render", "heavy_rain", "--out", str(wet)]) == 0
    assert main(["render", "heavy_rain", "--out", str(dry), "--no-effects"]) == 0
    with_effects = cv2.imread(str(wet / "front.png"))[..., ::-1]
    bare = cv2.imread(str(dry / "front.png"))[..., ::-1]
    assert np.abs(with_effects.astype(int) - bare).mean() > 5.0
    with Episode(load_scenario("heavy_rain")) as episode:
        first = episode.step().frames["front"]
    np.testing.assert_array_equal(with_effects, first)


def test_unknown_scenario_is_one_clear_error(capsys):
    assert main(["render", "no_such_scenario"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "no_such_scenario" in err[0]


def test_malformed_scenario_file_names_the_key(tmp_path, capsys):
    bad = tmp_path / "bad.toml"
    bad.write_text('name = "x"\ndescription = "y"\nspeeed = 3\n[[road.segments]]\n'
                   'kind = "straight"\nlength_m = 100\n')
    assert main(["render", str(bad), "--out", str(tmp_path)]) == 2
    err = capsys.readouterr().err
    assert "speeed" in err and "bad.toml" in err


def test_bench_single_model_adds_a_model_only_loop_per_front_model(tmp_path, capsys):
    """`--single-model` drives each scenario with each front model alone; the JSON keys those
    episodes SCENARIO@MODEL; a scenario given by path is reported by its file's stem."""
    import json
    from pathlib import Path

    from lanekeep.scenario.schema import load_scenario

    path = tmp_path / "short_straight.toml"
    path.write_text(Path(load_scenario("clear_straight").source).read_text())
    out = tmp_path / "bench.json"
    code = main(["bench", str(path), "--seconds", "0.3", "--workers", "2", "--single-model",
                 "--mode", "paper", "--json", str(out)])
    assert code == 0
    data = json.loads(out.read_text())
    assert sorted(data) == ["short_straight", "short_straight@hough",
                            "short_straight@sliding_window"]
    assert list(data["short_straight@hough"]["sources"]) == [
        "hough", "hough:track", "fused", "reference"]
    printed = capsys.readouterr().out
    assert "closed loop: MMAE vs each front model alone" in printed
    assert "sliding_window only" in printed and "best track" in printed
