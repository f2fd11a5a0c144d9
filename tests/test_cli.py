"""The thin CLI: scenarios listing, render snapshots, clear errors with exit code 2."""

from lanekeep.cli import main
from lanekeep.scenario import shipped_scenarios


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
