"""Sequences of frames and videos (lanekeep/realcam/frames.py): natural order, the checks made
before any frame is used, `PATH#N` labels, the annotated video written atomically and read back;
one camera for a sequence (camera_file.camera_for_frames)."""

from __future__ import annotations

import cv2
import numpy as np
import pytest
from realcam.road_frames import H, W, read_back, road, write_video  # tests/ is on sys.path

from lanekeep.realcam import camera_file
from lanekeep.realcam.frames import (
    DEFAULT_FPS,
    ImageSequence,
    VideoFrames,
    VideoOut,
    expand_folders,
    is_video,
    natural_key,
    open_sequence,
)

# --- Natural order --------------------------------------------------------------------------


def test_natural_key_compares_digit_runs_as_numbers():
    names = ["1_10.png", "frame.png", "1_4.png", "10_1.png", "2_1.png", "Frame2.png",
             "frame10.png", "a1.png", "a01.png", "1_9.png"]
    assert sorted(names, key=natural_key) == [
        "1_4.png", "1_9.png", "1_10.png", "2_1.png", "10_1.png",
        "a01.png", "a1.png", "frame.png", "Frame2.png", "frame10.png"]
    assert sorted(["b.png", "a.png", "C.png"], key=natural_key) == ["a.png", "b.png", "C.png"]


def test_a_folder_is_natural_for_sequences_and_sorted_for_photos(tmp_path):
    for name in ("1_10.png", "1_4.png", "1_9.png", ".hidden.png", "notes.txt"):
        cv2.imwrite(str(tmp_path / name), road()) if name.endswith(".png") else (
            tmp_path / name).write_text("x")
    natural, problems = expand_folders([str(tmp_path)], natural=True)
    assert problems == []
    assert [p.rsplit("/", 1)[1] for p in natural] == ["1_4.png", "1_9.png", "1_10.png"]
    plain, _ = expand_folders([str(tmp_path)])
    assert [p.rsplit("/", 1)[1] for p in plain] == ["1_10.png", "1_4.png", "1_9.png"]


# --- Image sequences ------------------------------------------------------------------------


def test_a_sequence_keeps_the_order_given_and_reads_rgb(tmp_path):
    paths = []
    for name, shift in (("b.png", 0.0), ("a.png", 0.2), ("c.png", 0.4)):
        cv2.imwrite(str(tmp_path / name), road(shift))
        paths.append(str(tmp_path / name))
    source, problems = open_sequence(paths)
    assert problems == [] and isinstance(source, ImageSequence)
    assert source.size == (W, H) and source.fps is None
    frames = list(source.frames())
    assert [(f.index, f.label) for f in frames] == [(k, p) for k, p in enumerate(paths)]
    np.testing.assert_array_equal(frames[1].image, road(0.2)[..., ::-1])


def test_mixed_sizes_are_one_problem_naming_the_first_other_frame(tmp_path):
    paths = []
    for name, size in (("0.png", (W, H)), ("1.png", (W, H)), ("2.png", (640, 360)),
                       ("3.png", (160, 90)), ("4.png", (W, H))):
        cv2.imwrite(str(tmp_path / name), road(size=size))
        paths.append(str(tmp_path / name))
    source, problems = open_sequence(paths)
    assert source is None
    assert len(problems) == 1
    assert problems[0].startswith(f"{paths[2]}: frame is 640x360 ")
    assert paths[0] in problems[0] and "320x180" in problems[0]


def test_unreadable_frames_are_a_problem_each(tmp_path):
    good = tmp_path / "good.png"
    cv2.imwrite(str(good), road())
    empty = tmp_path / "empty.png"
    empty.write_bytes(b"")
    source, problems = open_sequence([str(good), str(empty), str(tmp_path / "absent.png")])
    assert source is None and len(problems) == 2
    assert "empty file" in problems[0] and "no such file" in problems[1]


# --- Videos ---------------------------------------------------------------------------------


@pytest.mark.parametrize(("name", "fourcc"), [("clip.avi", "MJPG"), ("clip.mp4", "mp4v")])
def test_a_video_is_read_frame_by_frame_with_path_hash_index_labels(tmp_path, name, fourcc):
    frames = [road(0.1 * k) for k in range(4)]
    path = write_video(tmp_path / name, frames, fps=12.5, fourcc=fourcc)
    assert is_video(path)
    source, problems = open_sequence([path])
    assert problems == [] and isinstance(source, VideoFrames)
    assert source.size == (W, H) and source.fps == pytest.approx(12.5)
    got = list(source.frames())
    assert [f.label for f in got] == [f"{path}#{k}" for k in range(4)]
    assert [f.index for f in got] == [0, 1, 2, 3]
    assert all(f.image.shape == (H, W, 3) for f in got)
    # RGB, close to what was written (lossy codecs): the road's grey, the sky's blue in R
    assert abs(int(got[0].image[5, 5, 0]) - 120) < 12 and abs(int(got[0].image[5, 5, 2]) - 200) < 12


def test_a_video_file_of_another_suffix_is_found_by_its_content(tmp_path):
    path = write_video(tmp_path / "clip.avi", [road(), road()])
    renamed = tmp_path / "clip.dat"
    renamed.write_bytes(open(path, "rb").read())
    assert is_video(renamed)
    text = tmp_path / "notes.dat"
    text.write_text("no frames here\n")
    png = tmp_path / "still.dat"
    png.write_bytes(cv2.imencode(".png", road())[1].tobytes())
    assert not is_video(text) and not is_video(png) and not is_video(tmp_path / "absent.dat")


@pytest.mark.parametrize("case", ["garbage", "truncated", "empty", "missing"])
def test_an_unreadable_video_is_one_problem_naming_it(tmp_path, case):
    path = tmp_path / "clip.mp4"
    if case == "garbage":
        path.write_bytes(bytes(range(256)) * 16)
    elif case == "truncated":  # mp4v writes its index (moov) last: half a file has none
        data = open(write_video(tmp_path / "whole.mp4", [road()] * 4, fourcc="mp4v"), "rb").read()
        path.write_bytes(data[: len(data) // 2])
    elif case == "empty":
        path.write_bytes(b"")
    source, problems = open_sequence([str(path)])
    assert source is None and len(problems) == 1
    assert problems[0].startswith(f"{path}: ")
    if case == "missing":
        assert "no such file" in problems[0]


def test_a_video_must_be_the_only_input_of_a_sequence(tmp_path):
    video = write_video(tmp_path / "clip.avi", [road()])
    png = tmp_path / "a.png"
    cv2.imwrite(str(png), road())
    source, problems = open_sequence([str(png), video])
    assert source is None and len(problems) == 1
    assert problems[0].startswith(f"{video}: a video is a sequence of its own")


def test_a_video_without_a_frame_rate_gets_the_default(tmp_path, monkeypatch):
    path = write_video(tmp_path / "clip.avi", [road()])
    real = cv2.VideoCapture

    class NoRate:
        def __init__(self, *args):
            self._capture = real(*args)

        def get(self, prop):
            return 0.0 if prop == cv2.CAP_PROP_FPS else self._capture.get(prop)

        def __getattr__(self, name):
            return getattr(self._capture, name)

    monkeypatch.setattr(cv2, "VideoCapture", NoRate)
    source, _ = open_sequence([path])
    assert source.fps == DEFAULT_FPS


# --- The annotated video --------------------------------------------------------------------


def test_video_out_is_atomic_and_reads_back_with_its_frames_and_rate(tmp_path):
    target = tmp_path / "out.avi"
    frames = [road(0.1 * k) for k in range(5)]
    with VideoOut(target, 29.97, (W, H)) as out:
        for frame in frames:
            out.write(frame)
        assert not target.exists()  # only the hidden temporary file so far
    assert [p.name for p in tmp_path.iterdir()] == ["out.avi"]
    got, fps = read_back(target)
    assert len(got) == 5 and got[0].shape == (H, W, 3)
    assert fps == pytest.approx(29.97, abs=0.01)
    assert np.abs(got[3].astype(int) - frames[3]).mean() < 4.0  # Motion-JPEG: near, not exact


def test_video_out_leaves_nothing_when_aborted_or_empty(tmp_path):
    target = tmp_path / "out.avi"
    with pytest.raises(RuntimeError), VideoOut(target, 10.0, (W, H)) as out:
        out.write(road())
        raise RuntimeError("stopped")
    with pytest.raises(OSError, match="no video"), VideoOut(target, 10.0, (W, H)):
        pass
    with pytest.raises(ValueError, match="640x360"), VideoOut(target, 10.0, (W, H)) as out:
        out.write(road(size=(640, 360)))
    assert list(tmp_path.iterdir()) == []


# --- One camera for a sequence --------------------------------------------------------------


def test_a_sequence_camera_takes_the_median_horizon_of_its_frames(monkeypatch):
    found = iter([100.0, None, 80.0, 95.0])
    monkeypatch.setattr(camera_file, "horizon_row", lambda *args: next(found))
    frames = [np.zeros((H, W, 3), np.uint8)] * 4
    model, cam, horizon = camera_file.camera_for_frames(frames, None)
    assert horizon == 95.0  # the median of 100, 80 and 95; the frame with none does not count
    assert model.pitch_rad == pytest.approx(np.arctan((95.0 - cam.cy) / cam.fy))
    monkeypatch.setattr(camera_file, "horizon_row", lambda *args: None)
    assert camera_file.camera_for_frames(frames, None, horizon_fraction=0.5)[2] == 0.5 * H


def test_one_photo_gets_the_camera_it_always_got():
    image = road(size=(640, 360))[..., ::-1]
    one = camera_file.camera_for_image(image, None)
    same = camera_file.camera_for_frames([image], None)
    assert one[2] == same[2] and one[1] == same[1]
    np.testing.assert_array_equal(one[0].K, same[0].K)
