"""lanekeep/evaluation/detect_frames.py (`lanekeep detect` as a library): every input checked
before anything runs; each frame's line handed on as it is made; overlays named in the
sequence's order and written atomically; a failing overlay or a changed input stops the run
with its own error."""

from __future__ import annotations

import cv2
import numpy as np
import pytest
from realcam.road_frames import road  # tests/ is on sys.path

from lanekeep.detectors.config import load_config
from lanekeep.evaluation import detect_frames as df
from lanekeep.evaluation import real_frames


@pytest.fixture(scope="module")
def config():
    return load_config(None)


def _photos(folder, names) -> list[str]:
    folder.mkdir(parents=True, exist_ok=True)
    for k, name in enumerate(names):
        cv2.imwrite(str(folder / name), road(0.1 * k))
    return [str(folder / name) for name in names]


def test_sequence_overlays_sort_in_the_sequence_order():
    names = [df.frame_overlay_path("o", k, f"x/{k}_1.png", 12).name for k in (2, 10)]
    assert names == ["000002_2_1.png", "000010_10_1.png"] and sorted(names) == names
    assert df.frame_overlay_path("o", 7, "a.png", 10_000_000).name == "0000007_a.png"
    assert df.video_overlay_path("o", "clips/drive.mp4").name == "drive.avi"


def test_photo_problems_find_every_collision_and_video_before_anything_runs(tmp_path, config):
    a = _photos(tmp_path / "a", ["road.png"])
    b = _photos(tmp_path / "b", ["road.png"])
    request = df.DetectRequest("sliding_window", config, overlay=str(tmp_path / "out"))
    problems = df.photo_problems(request, [*a, *b])
    assert problems == [f"{b[0]}: its overlay {tmp_path / 'out' / 'road.png'} would overwrite "
                        f"that of {a[0]}"]
    own = df.DetectRequest("sliding_window", config, overlay=str(tmp_path / "a"))
    assert "would overwrite the image itself" in df.photo_problems(own, a)[0]
    missing = str(tmp_path / "absent.png")
    assert "no such file" in df.photo_problems(request, [missing])[0]
    assert not (tmp_path / "out").exists()  # checking creates nothing
    with pytest.raises(ValueError, match="no such file"):  # --debug: the exception itself
        df.photo_problems(df.DetectRequest("sliding_window", config, strict=True), [missing])


def test_refusals_make_the_overlay_folder_only_when_nothing_is_wrong(tmp_path, config):
    request = df.DetectRequest("sliding_window", config, overlay=str(tmp_path / "out" / "x"))
    assert df.refusals(request, ["a problem"]) == ["a problem"]
    assert not (tmp_path / "out").exists()
    assert df.refusals(request, []) == []
    assert (tmp_path / "out" / "x").is_dir() and list((tmp_path / "out" / "x").iterdir()) == []


class _Result:
    def __init__(self, image):
        self.mean = float(image.mean())

    def line(self, raw_file: str, fmt: str) -> dict:
        return {"raw_file": raw_file, "format": fmt, "mean": self.mean}

    def overlay(self, image):
        return image[..., ::-1].copy()


def test_photos_each_get_a_new_detector_their_line_and_overlay(tmp_path, config, monkeypatch):
    made = []

    def fake_detector(images, name, *_args):
        made.append(name)
        return _Result

    monkeypatch.setattr(real_frames, "frame_detector", fake_detector)
    photos = _photos(tmp_path / "in", ["b.png", "a.png"])
    request = df.DetectRequest("hough", config, format="tusimple",
                               overlay=str(tmp_path / "out"))
    (tmp_path / "out").mkdir()
    lines = []
    df.detect_photos(request, photos, lines.append)
    assert made == ["hough", "hough"]
    assert [(line["raw_file"], line["format"]) for line in lines] == [
        (photos[0], "tusimple"), (photos[1], "tusimple")]
    assert sorted(p.name for p in (tmp_path / "out").iterdir()) == ["a.png", "b.png"]
    back = cv2.imread(str(tmp_path / "out" / "b.png"))
    assert np.array_equal(back, cv2.imread(photos[0]))  # what overlay() drew (RGB -> BGR)


def test_a_photo_changed_since_its_check_or_an_overlay_not_written_stops_the_run(
        tmp_path, config, monkeypatch):
    monkeypatch.setattr(real_frames, "frame_detector", lambda *_args: _Result)
    photos = _photos(tmp_path / "in", ["a.png", "b.png"])
    (tmp_path / "in" / "b.png").write_bytes(b"")
    lines = []
    with pytest.raises(df.InputChanged, match="b.png"):
        df.detect_photos(df.DetectRequest("hough", config), photos, lines.append)
    assert len(lines) == 1  # the first photo's line came out before the run stopped
    (tmp_path / "blocked").write_text("a file where the overlay folder should be")
    request = df.DetectRequest("hough", config, overlay=str(tmp_path / "blocked"))
    with pytest.raises(df.OverlayError, match="cannot write the overlay") as caught:
        df.detect_photos(request, photos[:1], lines.append)
    assert caught.value.path == tmp_path / "blocked" / "a.png"


def test_a_detector_that_cannot_be_made_is_its_own_error(tmp_path, config, monkeypatch):
    def broken(*_args):
        raise ValueError("w.pt: not a LaneNet weights file")

    monkeypatch.setattr(real_frames, "frame_detector", broken)
    photos = _photos(tmp_path / "in", ["a.png"])
    with pytest.raises(df.DetectorUnavailable, match="w.pt: not a LaneNet") as caught:
        df.detect_photos(df.DetectRequest("lanenet", config), photos, print)
    assert isinstance(caught.value.__cause__, ValueError)
