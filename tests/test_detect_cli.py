"""`lanekeep detect`: bad inputs give one clear error line and exit 2; a photo gives output."""

import argparse
import json

import cv2
import numpy as np
import pytest

import lanekeep  # noqa: F401
from lanekeep import cli_detect


def _run(argv):
    parser = argparse.ArgumentParser(prog="lanekeep")
    cli_detect.register(parser.add_subparsers(dest="command", required=True))
    args = parser.parse_args(argv)
    return args.func(args)


def _bad_inputs(tmp_path):
    text = tmp_path / "notes.png"
    text.write_text("not an image at all\n")
    tiny = tmp_path / "tiny.png"
    cv2.imwrite(str(tiny), np.zeros((1, 1, 3), np.uint8))
    return {"missing": (tmp_path / "absent.jpg", "no such file"),
            "not an image": (text, "not an image"),
            "1x1": (tiny, "too small")}


@pytest.mark.parametrize("case", ["missing", "not an image", "1x1"])
@pytest.mark.parametrize("detector", ["hough", "sliding_window"])
def test_bad_input_is_one_error_line_and_exit_2(tmp_path, capsys, case, detector):
    path, message = _bad_inputs(tmp_path)[case]
    code = _run(["detect", str(path), "--detector", detector])
    out, err = capsys.readouterr()
    assert code == 2
    assert out == ""
    lines = err.strip().splitlines()
    assert len(lines) == 1 and message in lines[0] and str(path) in lines[0]


def _synthetic_dashcam_frame() -> np.ndarray:
    """A flat road seen by the default dashcam (60 deg hfov, 1.5 m, level), lanes 3.7 m apart."""
    image = np.full((720, 1280, 3), (95, 95, 95), np.uint8)
    image[:360] = (200, 170, 120)
    f = 640.0 / np.tan(np.radians(30.0))
    for y_lane in (1.85, -1.85):
        for x in np.arange(5.0, 80.0, 0.05):
            v = 359.5 + f * 1.5 / x
            u = 639.5 - f * y_lane / x
            cv2.circle(image, (int(u), int(v)), max(1, int(f * 0.075 / x)), (240, 240, 240), -1)
    return image


@pytest.mark.parametrize("fmt", ["tusimple", "json"])
def test_detect_writes_one_line_per_image_and_an_overlay(tmp_path, capsys, fmt):
    frame = tmp_path / "road.png"
    cv2.imwrite(str(frame), _synthetic_dashcam_frame())
    code = _run(["detect", str(frame), str(frame), "--detector", "sliding_window",
                 "--format", fmt, "--overlay", str(tmp_path / "ov")])
    out, _ = capsys.readouterr()
    assert code == 0
    lines = [json.loads(line) for line in out.strip().splitlines()]
    assert len(lines) == 2 and lines[0]["raw_file"] == str(frame)
    if fmt == "tusimple":
        assert len(lines[0]["lanes"]) == 2
        assert all(len(lane) == len(lines[0]["h_samples"]) for lane in lines[0]["lanes"])
    else:
        assert lines[0]["valid"] and abs(lines[0]["offset_m"]) < 0.15
    assert (tmp_path / "ov" / "road.png").exists()
