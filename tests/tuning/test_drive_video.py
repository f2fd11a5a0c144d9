"""A rendered drive as a video and its camera file, read back by `lanekeep detect --sequence`."""

import json

from lanekeep.cli.main import main as lanekeep_main
from lanekeep.realcam.camera_file import read_camera_file
from lanekeep.tuning.drive_video import main
from lanekeep.world.camera_mount import DASHCAM_HEIGHT_M, DASHCAM_PITCH_DEG


def test_a_drive_video_is_read_by_detect_with_its_camera(tmp_path, capsys):
    out = tmp_path / "drive.avi"
    assert main(["clear_straight", "--seconds", "0.5", "--size", "320x180",
                 "--out", str(out)]) == 0
    camera = read_camera_file(tmp_path / "drive.camera.toml")
    # clear_straight's front camera is the dashcam preset (#59): 1.4 m, 3.07 deg down
    assert (camera.width, camera.height, camera.height_m) == (320, 180, DASHCAM_HEIGHT_M)
    assert abs(camera.pitch_deg - DASHCAM_PITCH_DEG) < 0.01
    capsys.readouterr()
    assert lanekeep_main(["detect", "--sequence", str(out), "--camera",
                          str(tmp_path / "drive.camera.toml"), "--detector", "hough"]) == 0
    rows = [json.loads(line) for line in capsys.readouterr().out.splitlines()]
    assert [r["raw_file"] for r in rows] == [f"{out}#{i}" for i in range(5)]


def test_bad_arguments_are_one_line(tmp_path, capsys):
    assert main(["clear_straight", "--size", "big", "--out", str(tmp_path / "a.avi")]) == 2
    assert main(["clear_straight", "--out", str(tmp_path / "a.mp4")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 2 and all(line.startswith("drive_video: error: ") for line in err)
