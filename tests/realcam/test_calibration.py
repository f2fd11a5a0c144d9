"""`lanekeep calibrate` on chessboards rendered by the simulator recovers the camera's fx."""

import argparse

import cv2
import pytest

import lanekeep  # noqa: F401
from lanekeep.cli import detect as cli_detect
from lanekeep.realcam.camera_file import read_camera_file
from lanekeep.sensing.chessboard import render_chessboards


def _run(argv):
    parser = argparse.ArgumentParser(prog="lanekeep")
    cli_detect.register(parser.add_subparsers(dest="command", required=True))
    args = parser.parse_args(argv)
    return args.func(args)


@pytest.fixture(scope="module")
def boards(tmp_path_factory):
    images, camera = render_chessboards(n_views=10, seed=0)
    folder = tmp_path_factory.mktemp("boards")
    paths = []
    for i, image in enumerate(images):
        path = folder / f"board_{i:02d}.png"
        cv2.imwrite(str(path), image[..., ::-1])
        paths.append(str(path))
    return paths, camera


def test_calibrate_recovers_fx_within_one_percent(boards, tmp_path, capsys):
    paths, camera = boards
    junk = tmp_path / "junk.png"
    junk.write_text("no image")
    out_file = tmp_path / "camera.toml"
    code = _run(["calibrate", *paths, str(junk), "--pattern", "9x6", "--out", str(out_file)])
    out, _ = capsys.readouterr()
    assert code == 0
    assert "reprojection RMS" in out and f"not used: {junk}" in out
    cam = read_camera_file(out_file)
    assert (cam.width, cam.height) == (1280, 720)
    assert cam.fx == pytest.approx(camera.fx, rel=0.01)
    assert cam.fy == pytest.approx(camera.fy, rel=0.01)


def test_too_few_boards_is_a_clear_error(boards, tmp_path, capsys):
    paths, _ = boards
    code = _run(["calibrate", *paths[:2], "--out", str(tmp_path / "c.toml")])
    _, err = capsys.readouterr()
    assert code == 2
    assert "need at least 5" in err and not (tmp_path / "c.toml").exists()
