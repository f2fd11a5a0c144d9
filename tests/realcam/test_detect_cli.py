"""`lanekeep detect`: bad inputs give one clear error line and exit 2; a photo gives output."""

import argparse
import json
from functools import partial

import cv2
import numpy as np
import pytest
from cli.error_lines import one_error_line  # tests/ is on sys.path

import lanekeep  # noqa: F401
from lanekeep.cli import detect as cli_detect


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


# --- Damaged files, wrong sizes, unwritable outputs: all found before anything runs ---------

def _jpeg_bytes() -> bytes:
    return cv2.imencode(".jpg", _synthetic_dashcam_frame())[1].tobytes()


def _png_bytes() -> bytes:
    return cv2.imencode(".png", _synthetic_dashcam_frame())[1].tobytes()


def _with_exif_thumbnail(jpeg: bytes) -> bytes:
    """`jpeg` with an APP1 segment holding a whole small JPEG (its own FF D9 inside)."""
    thumb = cv2.imencode(".jpg", np.full((60, 80, 3), 128, np.uint8))[1].tobytes()
    payload = b"Exif\x00\x00" + thumb
    return jpeg[:2] + b"\xff\xe1" + (len(payload) + 2).to_bytes(2, "big") + payload + jpeg[2:]


def _damaged(tmp_path, case):
    """(path, words the error line must hold) for one kind of bad image file."""
    jpeg, png = _jpeg_bytes(), _png_bytes()
    files = {
        "truncated jpeg": ("cut.jpg", jpeg[: int(len(jpeg) * 0.6)], "truncated JPEG"),
        "truncated png": ("cut.png", png[: int(len(png) * 0.6)], "truncated PNG"),
        # A cut file padded with zeros (a preallocated dashcam file): zeros after the end
        # marker are fine (see the good cases), zeros instead of it are not.
        "zero-padded cut jpeg": ("pad.jpg", jpeg[: len(jpeg) // 2] + bytes(len(jpeg) // 2),
                                 "truncated JPEG"),
        # The thumbnail's end marker must not pass for the photo's.
        "cut jpeg with thumbnail": ("thumb.jpg", _with_exif_thumbnail(jpeg)[: len(jpeg) // 2],
                                    "truncated JPEG"),
        # Cut, then given an end marker: libjpeg decodes it with a warning; it is an error here.
        "corrupt jpeg": ("corrupt.jpg", jpeg[: int(len(jpeg) * 0.6)] + b"\xff\xd9",
                         "corrupt JPEG"),
        "corrupt png": ("crc.png", png[:100] + bytes([png[100] ^ 0xFF]) + png[101:],
                        "corrupt PNG"),
        "empty": ("empty.jpg", b"", "empty file"),
        "text named .jpg": ("x.jpg", b"lane markings, honest\n", "not an image"),
    }
    if case == "missing":
        return tmp_path / "absent.jpg", "no such file"
    name, data, words = files[case]
    path = tmp_path / name
    path.write_bytes(data)
    return path, words


DAMAGED = ["truncated jpeg", "truncated png", "zero-padded cut jpeg", "cut jpeg with thumbnail",
           "corrupt jpeg", "corrupt png", "empty", "text named .jpg", "missing"]


detect_error_line = partial(one_error_line, start="lanekeep detect: error: ")


@pytest.mark.parametrize("case", DAMAGED)
def test_damaged_image_is_one_error_line_exit_2_and_no_output(tmp_path, capsys, case):
    path, words = _damaged(tmp_path, case)
    overlay = tmp_path / "ov"
    code = _run(["detect", str(path), "--detector", "hough", "--overlay", str(overlay)])
    detect_error_line(capsys, code, str(path), words)
    assert not overlay.exists()


def test_truncated_jpeg_through_main_prints_only_one_line_at_fd_level(tmp_path, capfd):
    """No libjpeg or OpenCV warning reaches stderr besides the error line (fd 2, not sys.stderr)."""
    from lanekeep.cli.main import main

    for case in ("truncated jpeg", "corrupt jpeg", "truncated png"):
        path, words = _damaged(tmp_path, case)
        detect_error_line(capfd, main(["detect", str(path)]), str(path), words)


def test_debug_lets_the_image_error_through(tmp_path):
    from lanekeep.cli.main import main
    from lanekeep.realcam.image_io import ImageError

    path, _ = _damaged(tmp_path, "truncated jpeg")
    with pytest.raises(ImageError, match="truncated JPEG"):
        main(["--debug", "detect", str(path)])


def test_one_bad_image_among_good_ones_stops_everything(tmp_path, capsys):
    good = tmp_path / "good.jpg"
    good.write_bytes(_jpeg_bytes())
    bad, _ = _damaged(tmp_path, "truncated jpeg")
    empty, _ = _damaged(tmp_path, "empty")
    overlay = tmp_path / "ov"
    code = _run(["detect", str(good), str(bad), str(good), str(empty), "--overlay", str(overlay)])
    out, err = capsys.readouterr()
    assert code == 2
    assert out == ""  # no detection ran, not even for the good image before the bad one
    lines = err.strip().splitlines()
    assert len(lines) == 2 and str(bad) in lines[0] and str(empty) in lines[1]
    assert "Traceback" not in err
    assert not overlay.exists()


def _camera_file(tmp_path, width=1280, height=720):
    from lanekeep.realcam.camera_file import default_camera, write_camera_file

    path = tmp_path / "camera.toml"
    write_camera_file(path, default_camera(width, height))
    return path


def test_image_of_another_size_than_the_camera_file_is_rejected(tmp_path, capsys):
    camera = _camera_file(tmp_path)
    small = tmp_path / "small.png"
    cv2.imwrite(str(small), cv2.resize(_synthetic_dashcam_frame(), (640, 360)))
    code = _run(["detect", str(small), "--camera", str(camera)])
    detect_error_line(capsys, code, str(small), "640x360", "1280x720", str(camera))


@pytest.mark.parametrize("where", ["below a file", "is a file"])
def test_unwritable_overlay_folder_is_found_before_detection(tmp_path, capsys, where):
    frame = tmp_path / "road.png"
    cv2.imwrite(str(frame), _synthetic_dashcam_frame())
    blocker = tmp_path / "blocker"
    blocker.write_text("a regular file\n")
    overlay = blocker / "ov" if where == "below a file" else blocker
    code = _run(["detect", str(frame), "--overlay", str(overlay)])
    detect_error_line(capsys, code, str(overlay))  # before any detection ran: no output
    assert blocker.read_text() == "a regular file\n"


def test_overlays_that_would_overwrite_each_other_are_rejected(tmp_path, capsys):
    (tmp_path / "a").mkdir()
    (tmp_path / "b").mkdir()
    for d in ("a", "b"):
        cv2.imwrite(str(tmp_path / d / "road.png"), _synthetic_dashcam_frame())
    code = _run(["detect", str(tmp_path / "a" / "road.png"), str(tmp_path / "b" / "road.png"),
                 "--overlay", str(tmp_path / "ov")])
    detect_error_line(capsys, code, str(tmp_path / "b" / "road.png"), "would overwrite")
    # ... and an overlay folder holding the input would overwrite the photo itself.
    code = _run(["detect", str(tmp_path / "a" / "road.png"), "--overlay", str(tmp_path / "a")])
    detect_error_line(capsys, code, "would overwrite the image itself")


def test_good_jpeg_with_camera_file_and_trailing_bytes_works(tmp_path, capsys):
    """Bytes after the end-of-image marker (zero padding, a motion photo's video) are fine."""
    frame = tmp_path / "road.jpg"
    frame.write_bytes(_with_exif_thumbnail(_jpeg_bytes()) + bytes(256) + b"ftypmp42 video")
    overlay = tmp_path / "ov"
    code = _run(["detect", str(frame), "--camera", str(_camera_file(tmp_path)),
                 "--overlay", str(overlay)])
    out, err = capsys.readouterr()
    assert code == 0, err
    assert err == ""
    assert json.loads(out)["raw_file"] == str(frame)
    assert [p.name for p in overlay.iterdir()] == ["road.png"]  # no temporary files left
    assert cv2.imread(str(overlay / "road.png")).shape == (720, 1280, 3)


def test_read_image_returns_rgb(tmp_path):
    from lanekeep.realcam.image_io import read_image

    bgr = np.zeros((80, 100, 3), np.uint8)
    bgr[..., 2] = 255  # red in OpenCV's BGR
    path = tmp_path / "red.png"
    cv2.imwrite(str(path), bgr)
    rgb = read_image(path)
    assert rgb.shape == (80, 100, 3) and rgb.dtype == np.uint8
    assert (rgb[..., 0] == 255).all() and (rgb[..., 2] == 0).all()


def test_calibrate_out_below_a_file_is_rejected_before_calibrating(tmp_path, capsys):
    blocker = tmp_path / "blocker"
    blocker.write_text("x\n")
    code = _run(["calibrate", str(tmp_path / "absent.png"), "--out",
                 str(blocker / "camera.toml")])
    out, err = capsys.readouterr()
    assert code == 2 and out == ""
    lines = err.strip().splitlines()
    assert len(lines) == 1 and "lanekeep calibrate: error:" in lines[0]
    assert str(blocker / "camera.toml") in lines[0] and "Traceback" not in err
