"""`lanekeep detect --sequence`: frames in order or a video through one detector that keeps its
state, one JSON line per frame (`raw_file` the frame's path or `VIDEO#N`), overlays as numbered
PNGs or an annotated video; bad input (mixed sizes, an unreadable video, a video without
--sequence) is one error line, exit 2, nothing written.

LaneNet here is an untrained small network saved to tmp_path (as in test_lanenet_cli.py): these
tests prove that its state is carried, not how well it detects."""

from __future__ import annotations

import dataclasses
import json
from functools import partial

import cv2
import numpy as np
import pytest
import torch
from cli.error_lines import one_error_line  # tests/ is on sys.path
from realcam.road_frames import H, W, read_back, road, write_video  # tests/ is on sys.path

from lanekeep.cli.main import main

N = 4  # frames per test sequence


@pytest.fixture(scope="module")
def weights(tmp_path_factory) -> str:
    """An untrained small LaneNet (seeded) whose objectness bias makes every cell a proposal,
    so that boundaries are fitted whatever the random initialisation gives."""
    from lanekeep.detectors.lanenet import save_weights
    from lanekeep.detectors.lanenet_model import LaneNet, LaneNetConfig

    torch.manual_seed(0)
    config = LaneNetConfig(width=160, height=88, channels=(8, 16, 16), hidden=8, head=16)
    model = LaneNet(config)
    with torch.no_grad():
        for j in range(config.rows_per_cell):  # head channels per sub-row: objectness first
            model.head[-1].bias[j * (3 + config.n_slots)] = 20.0
    path = tmp_path_factory.mktemp("weights") / "small.pt"
    save_weights(model, path)
    return str(path)


def _level_camera(tmp_path) -> str:
    """The default dashcam at the frames' size with its pitch given: the same camera for a
    sequence and for its frames one by one."""
    from lanekeep.realcam.camera_file import default_camera, write_camera_file

    path = tmp_path / "camera.toml"
    write_camera_file(path, dataclasses.replace(default_camera(W, H), pitch_deg=0.0))
    return str(path)


def _frames(folder, names=("1_10", "1_4", "1_9", "2_1")) -> list[str]:
    """Road frames, the car drifting left 0.1 m a frame in natural order of `names`."""
    folder.mkdir(exist_ok=True)
    order = sorted(names, key=lambda n: [int(p) for p in n.split("_")])
    for name in names:
        cv2.imwrite(str(folder / f"{name}.png"), road(0.1 * order.index(name)))
    return [str(folder / f"{name}.png") for name in order]


def _lines(out: str) -> list[dict]:
    return [json.loads(line) for line in out.strip().splitlines()]


_one_error_line = partial(one_error_line, start="lanekeep detect: error: ")

# --- Frames ---------------------------------------------------------------------------------


@pytest.mark.parametrize("fmt", ["json", "tusimple"])
def test_a_folder_runs_in_natural_order_with_one_line_per_frame(tmp_path, capsys, fmt):
    ordered = _frames(tmp_path / "clip")
    overlay = tmp_path / "ov"
    code = main(["detect", "--sequence", str(tmp_path / "clip"), "--detector", "sliding_window",
                 "--format", fmt, "--overlay", str(overlay)])
    out, err = capsys.readouterr()
    assert code == 0, err
    lines = _lines(out)
    assert [line["raw_file"] for line in lines] == ordered  # 1_4, 1_9, 1_10, 2_1
    if fmt == "json":
        assert len({line["horizon_row"] for line in lines}) == 1  # one camera for the sequence
        assert all(line["valid"] for line in lines)
        offsets = [line["offset_m"] for line in lines]
        assert all(b > a for a, b in zip(offsets, offsets[1:], strict=False))  # drifting left
    names = sorted(p.name for p in overlay.iterdir())
    assert names == ["000000_1_4.png", "000001_1_9.png", "000002_1_10.png", "000003_2_1.png"]
    assert cv2.imread(str(overlay / names[0])).shape == (H, W, 3)


def test_files_run_in_the_order_given(tmp_path, capsys):
    ordered = _frames(tmp_path / "clip")
    given = [ordered[2], ordered[0], ordered[3]]
    assert main(["detect", "--sequence", *given]) == 0
    assert [line["raw_file"] for line in _lines(capsys.readouterr().out)] == given


def _detectors_made(monkeypatch) -> list:
    """Every detector the registry makes from now on (the real ones, recorded)."""
    from lanekeep.detectors import registry

    made, real = [], registry.make_detector

    def spy(*args, **kwargs):
        made.append(real(*args, **kwargs))
        return made[-1]

    monkeypatch.setattr(registry, "make_detector", spy)
    return made


def test_lanenet_keeps_its_state_through_the_sequence(tmp_path, capsys, monkeypatch, weights):
    ordered = _frames(tmp_path / "clip")
    made = _detectors_made(monkeypatch)
    lanenet = ["--detector", "lanenet", "--weights", weights, "--camera", _level_camera(tmp_path)]
    code = main(["detect", "--sequence", *ordered, *lanenet])
    out, err = capsys.readouterr()
    assert code == 0, err
    sequence = _lines(out)
    assert [line["raw_file"] for line in sequence] == ordered
    assert all("boundaries" in line for line in sequence)
    assert len(made) == 1  # one detector for the whole sequence ...
    assert made[0]._state is not None and not made[0].last.scene_change  # ... its memory carried
    # Photo mode: a fresh detector per photo, no memory, the same camera. The first frame reads
    # the same, the later ones differ: what the sequence's GRU remembered changed them.
    made.clear()
    assert main(["detect", *ordered, *lanenet]) == 0
    photos = _lines(capsys.readouterr().out)
    assert len(made) == N
    assert photos[0]["boundaries"] == sequence[0]["boundaries"]
    assert all(p["boundaries"] != s["boundaries"]
               for p, s in zip(photos[1:], sequence[1:], strict=True))


# --- Videos ---------------------------------------------------------------------------------


@pytest.mark.parametrize(("name", "fourcc"), [("drive.mp4", "mp4v"), ("drive.avi", "MJPG")])
def test_a_video_gives_a_line_per_frame_and_an_annotated_video(tmp_path, capsys, name, fourcc):
    video = write_video(tmp_path / name, [road(0.1 * k) for k in range(N)], fps=15.0,
                        fourcc=fourcc)
    overlay = tmp_path / "ov"
    code = main(["detect", "--sequence", video, "--overlay", str(overlay)])
    out, err = capsys.readouterr()
    assert code == 0, err
    lines = _lines(out)
    assert [line["raw_file"] for line in lines] == [f"{video}#{k}" for k in range(N)]
    assert all(line["valid"] for line in lines)
    assert [p.name for p in overlay.iterdir()] == ["drive.avi"]  # no temporary file left
    frames, fps = read_back(overlay / "drive.avi")
    assert len(frames) == N and frames[0].shape == (H, W, 3)
    assert fps == pytest.approx(15.0)
    # annotated: the drawn lanes (green, red) and the horizon (yellow) are on it
    assert (np.abs(frames[0].astype(int) - road()).max(axis=2) > 100).sum() > 200


# --- Bad input: one line, exit 2, nothing written -------------------------------------------


def test_mixed_sizes_are_one_error_naming_the_first_other_frame(tmp_path, capsys):
    ordered = _frames(tmp_path / "clip")
    big = tmp_path / "big.png"
    cv2.imwrite(str(big), road(size=(640, 360)))
    overlay = tmp_path / "ov"
    code = main(["detect", "--sequence", ordered[0], str(big), ordered[1], str(big),
                 "--overlay", str(overlay)])
    _one_error_line(capsys, code, f"{big}: frame is 640x360", ordered[0], "320x180")
    assert not overlay.exists()


@pytest.mark.parametrize("case", ["garbage", "truncated"])
def test_an_unreadable_video_is_one_line_even_at_fd_level(tmp_path, capfd, case):
    """FFmpeg's own complaints (written to fd 2) do not reach the user."""
    path = tmp_path / "drive.mp4"
    if case == "garbage":
        path.write_bytes(bytes(range(256)) * 16)
    else:
        data = open(write_video(tmp_path / "whole.mp4", [road()] * N, fourcc="mp4v"), "rb").read()
        path.write_bytes(data[: len(data) // 2])
    overlay = tmp_path / "ov"
    code = main(["detect", "--sequence", str(path), "--overlay", str(overlay)])
    _one_error_line(capfd, code, f"{path}: cannot read it as a video")
    assert not overlay.exists()


def test_a_video_without_sequence_is_one_error_naming_the_flag(tmp_path, capsys):
    video = write_video(tmp_path / "drive.avi", [road()] * 2)
    png = tmp_path / "a.png"
    cv2.imwrite(str(png), road())
    overlay = tmp_path / "ov"
    code = main(["detect", str(png), video, "--overlay", str(overlay)])
    _one_error_line(capsys, code, video, "--sequence")
    assert not overlay.exists()


def test_a_video_among_frames_is_one_error(tmp_path, capsys):
    video = write_video(tmp_path / "drive.avi", [road()] * 2)
    png = tmp_path / "a.png"
    cv2.imwrite(str(png), road())
    code = main(["detect", "--sequence", str(png), video])
    _one_error_line(capsys, code, video, "a sequence of its own")


def test_an_overlay_that_would_overwrite_the_video_is_refused(tmp_path, capsys):
    video = write_video(tmp_path / "drive.avi", [road()] * 2)
    before = open(video, "rb").read()
    code = main(["detect", "--sequence", video, "--overlay", str(tmp_path)])
    _one_error_line(capsys, code, video, "would overwrite the video itself")
    assert open(video, "rb").read() == before


def test_frames_of_another_size_than_the_camera_file_are_one_error(tmp_path, capsys):
    from lanekeep.realcam.camera_file import default_camera, write_camera_file

    ordered = _frames(tmp_path / "clip")
    camera = tmp_path / "camera.toml"
    write_camera_file(camera, default_camera(1280, 720))
    code = main(["detect", "--sequence", *ordered, "--camera", str(camera)])
    _one_error_line(capsys, code, ordered[0], "320x180", "1280x720", str(camera))
