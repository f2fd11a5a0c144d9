"""A closed-loop drive's front camera as a video, with that camera's file, for trying
`lanekeep detect --sequence` on frames whose camera is known exactly.

    python -m lanekeep.tuning.drive_video case3_mild_turn_shade_bumps --seconds 8 \\
        --out out/drive.avi
    lanekeep detect --sequence out/drive.avi --camera out/drive.camera.toml \\
        --detector lanenet --overlay out/drive_overlay

The scenario runs as `lanekeep run` runs it (its seed, its controller); each control period's
front frame, as the car's detectors saw it, goes to a Motion-JPEG .avi at the control rate, and
the front camera's intrinsics, lens, mounting height and pitch (the car's spec sheet, not the
truth of any frame) to a camera TOML beside it (`<out stem>.camera.toml`).
"""

from __future__ import annotations

import argparse
import dataclasses
import math
import sys
from pathlib import Path

import numpy as np

from lanekeep.geometry.camera_model import CameraModel
from lanekeep.realcam.camera_file import CameraFile, write_camera_file


def camera_file_of(camera: CameraModel, distortion: np.ndarray | None) -> CameraFile:
    """A rendered camera as a camera file: its K, its lens, its height, and the pitch that puts
    the horizon where the model does (the camera file's convention, + = looking up)."""
    k = camera.K
    pitch_deg = math.degrees(math.atan((camera.horizon_row() - k[1, 2]) / k[1, 1]))
    lens = tuple(float(x) for x in distortion) if distortion is not None else (0.0,) * 5
    return CameraFile(camera.width, camera.height, float(k[0, 0]), float(k[1, 1]),
                      float(k[0, 2]), float(k[1, 2]), lens, float(camera.position_m[2]),
                      pitch_deg)


def write_drive(scenario_name: str, seconds: float, out: Path,
                size: tuple[int, int] | None = None) -> tuple[int, Path]:
    """(frames written, camera file) of `seconds` of the scenario's drive into `out`."""
    import cv2

    from lanekeep.core.files import atomic_path
    from lanekeep.loop.episode import Episode
    from lanekeep.scenario.schema import load_scenario

    scenario = dataclasses.replace(load_scenario(scenario_name), duration_s=seconds)
    camera_path = out.with_name(out.stem + ".camera.toml")
    with Episode(scenario, render_size=size) as episode, atomic_path(out) as tmp:
        simulator = episode.simulator
        write_camera_file(camera_path, camera_file_of(simulator.cameras["front"],
                                                      simulator.distortions["front"]),
                          f"front camera of {scenario_name} (python -m lanekeep.tuning."
                          f"drive_video)")
        writer, frames = None, 0
        try:
            for _ in range(episode.total_steps):
                frame = episode.observe().frames["front"]
                if writer is None:
                    h, w = frame.shape[:2]
                    writer = cv2.VideoWriter(str(tmp), cv2.VideoWriter_fourcc(*"MJPG"),
                                             1.0 / episode.dt_s, (w, h))
                writer.write(cv2.cvtColor(frame, cv2.COLOR_RGB2BGR))
                frames += 1
                episode.act()
        finally:
            if writer is not None:
                writer.release()
    return frames, camera_path


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("scenario", help="shipped scenario name or .toml path")
    parser.add_argument("--seconds", type=float, default=8.0)
    parser.add_argument("--out", type=Path, default=Path("out/drive.avi"), help=".avi file")
    parser.add_argument("--size", default=None, help="WxH (default: the scenario's camera)")
    args = parser.parse_args(argv)
    size = None
    if args.size:
        try:
            w, h = (int(v) for v in args.size.lower().split("x"))
            size = (w, h)
        except ValueError:
            print(f"drive_video: error: --size must be WxH, got {args.size!r}", file=sys.stderr)
            return 2
    if args.out.suffix.lower() != ".avi" or not args.seconds > 0:
        print("drive_video: error: --out must be an .avi file and --seconds > 0", file=sys.stderr)
        return 2
    args.out.parent.mkdir(parents=True, exist_ok=True)
    frames, camera = write_drive(args.scenario, args.seconds, args.out, size)
    print(f"{frames} frames -> {args.out}; camera -> {camera}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
