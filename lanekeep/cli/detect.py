"""`lanekeep detect` (lane detectors on real photos) and `lanekeep calibrate`.

Thin: argument parsing and output; the work is in lanekeep/evaluation/detect_frames.py (the
checks before anything runs, the photo and sequence runs, the overlays' files),
lanekeep/evaluation/real_frames.py (a detector on real frames: its camera, its output line, its
overlay), lanekeep/realcam/frames.py (photos, sequences, videos) and
lanekeep/realcam/calibration.py. Images are read by
lanekeep/realcam/image_io.py, which rejects missing, empty, truncated and corrupt files. `detect`
checks every input (and the overlay folder) before it runs anything: one bad input and nothing
is detected or written. `detect --sequence` runs one detector through a sequence of frames or a
video, keeping its state (LaneNet's memory) from frame to frame.
Exit codes: 0 success, 1 a failure while running (an overlay that could not be written),
2 bad input (a missing, empty, truncated, corrupt or wrongly sized image, a sequence of mixed
sizes, a video that cannot be read or given without --sequence, an output folder that cannot be
written, a weights file that is missing, empty, corrupt or of another architecture, too
few chessboards); each bad input is one "lanekeep CMD: error:" line.

A detector that sees every boundary (LaneNet: `detector.last.boundaries`) reports them all: in
TuSimple output as lanes ordered left to right, in JSON as "boundaries" with their slot names,
in overlays each in its own colour with its slot name; the classical detectors report their ego
pair and, in JSON as "others" (polynomials like "left" and "right") and in the TuSimple lanes
and overlays after the pair, the other lanes' lines they found.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from lanekeep.cli.outputs import error_line
from lanekeep.core.files import atomic_path, folder_problem
from lanekeep.evaluation.real_frames import (  # noqa: F401 - SLOT_COLOURS: public here too
    SEQUENCE_HORIZON_FRAMES,
    SLOT_COLOURS,
    draw_overlay,
)

_overlay = draw_overlay  # its name here before it moved to the library

EXIT_OK, EXIT_FAILURE, EXIT_BAD_INPUT = 0, 1, 2


def _error(command: str, message: str) -> int:
    """detect's and calibrate's lines name files: kept as they are, spaces and all."""
    return error_line(command, message, one_line=False)


def _print_line(line: dict) -> None:
    print(json.dumps(line), flush=True)


def cmd_detect(args: argparse.Namespace) -> int:
    from lanekeep.detectors.config import load_config
    from lanekeep.evaluation import detect_frames as df
    from lanekeep.realcam.camera_file import read_camera_file
    from lanekeep.realcam.frames import expand_folders

    debug = getattr(args, "debug", False)  # `lanekeep --debug`: the exception, traceback
    try:
        config = load_config(args.config)
        camera_file = read_camera_file(args.camera) if args.camera else None
    except (OSError, ValueError) as err:
        if debug:
            raise
        if isinstance(err, OSError) and err.filename:
            return _error("detect", f"{err.filename}: cannot read it: {err.strerror or err}")
        return _error("detect", str(err))
    request = df.DetectRequest(args.detector, config, camera_file, args.camera, args.weights,
                               args.format, args.overlay, strict=debug)
    # All inputs first: a bad one stops the command before any detection or output.
    if args.sequence:
        source, problems = df.sequence_problems(request, args.images)
    else:
        args.images, problems = expand_folders(args.images)
        problems += df.photo_problems(request, args.images)
    problems = df.refusals(request, problems)
    for problem in problems:
        _error("detect", problem)
    if problems:
        return EXIT_BAD_INPUT
    try:
        if args.sequence:
            df.detect_sequence(request, source, _print_line)
        else:
            df.detect_photos(request, args.images, _print_line)
    except df.OverlayError as err:
        _error("detect", str(err))
        return EXIT_FAILURE
    except (df.InputChanged, df.DetectorUnavailable) as err:
        if debug and isinstance(err, df.DetectorUnavailable):
            raise
        return _error("detect", str(err))
    return EXIT_OK


def cmd_calibrate(args: argparse.Namespace) -> int:
    from lanekeep.realcam.calibration import CalibrationError, calibrate, parse_pattern
    from lanekeep.realcam.camera_file import write_camera_file
    from lanekeep.realcam.image_io import read_image

    try:
        pattern = parse_pattern(args.pattern)
    except ValueError as err:
        return _error("calibrate", str(err))
    out = Path(args.out)
    if out.is_dir():
        return _error("calibrate", f"{args.out}: is a folder; --out names the camera file")
    problem = folder_problem(out.parent)
    if problem:
        return _error("calibrate", f"--out {args.out}: {problem}")
    images, unreadable = [], []
    for path in args.images:
        try:
            images.append((str(path), read_image(path)))
        except ValueError as err:
            unreadable.append((str(path), str(err)))
    try:
        result = calibrate(images, pattern, min_images=args.min_images, height_m=args.height_m)
    except CalibrationError as err:
        for name, why in unreadable:
            print(f"not used: {name}: {why}", file=sys.stderr)
        return _error("calibrate", str(err))
    cam = result.camera
    try:  # a temporary file renamed into place: never a half-written camera file
        out.parent.mkdir(parents=True, exist_ok=True)
        with atomic_path(out) as tmp:
            write_camera_file(tmp, cam, comment=(
                f"lanekeep calibrate: {len(result.used)} images, pattern {args.pattern}, "
                f"reprojection RMS {result.rms_px:.3f} px"))
    except OSError as err:
        return _error("calibrate", f"{args.out}: cannot write the camera file: "
                                   f"{err.strerror or err}")
    print(f"reprojection RMS {result.rms_px:.3f} px over {len(result.used)} images")
    print(f"fx {cam.fx:.2f} fy {cam.fy:.2f} cx {cam.cx:.2f} cy {cam.cy:.2f} "
          f"distortion {', '.join(f'{d:.4g}' for d in cam.distortion)}")
    for name, why in unreadable + result.rejected:
        print(f"not used: {name}: {why}")
    print(f"wrote {args.out}")
    return EXIT_OK


def register(subparsers) -> None:
    """Add the `detect` and `calibrate` subcommands (each sets func(args) -> exit code)."""
    from lanekeep.detectors.registry import known_detectors

    p = subparsers.add_parser(
        "detect", help="run a lane detector on real road photos",
        description="Without --camera the camera is an unknown 1.5 m high dashcam with a "
                    "60 deg horizontal field of view whose pitch is taken from each image's "
                    "vanishing point (detectors/config.py DashcamDefaults). A folder stands for "
                    "its images (PNG, JPEG, BMP, TIFF, WebP; not its subfolders) in sorted order. "
                    "All images are checked before "
                    "any is processed: if one is missing, empty, truncated, corrupt, not an "
                    "image, too small or (with --camera) not the camera file's size, or the "
                    "--overlay folder cannot be written, or the weights file cannot be loaded, "
                    "each problem is one error line, "
                    "nothing is detected or written, and the exit code is 2. With --sequence "
                    "the inputs are one sequence (frames in the order given, a folder's in "
                    "natural order: 1_4 before 1_10) or one video file, all of one size, run "
                    "through one detector that keeps its state, one camera for all frames "
                    f"(horizon: the median over the first {SEQUENCE_HORIZON_FRAMES}).")
    p.add_argument("images", nargs="+", metavar="IMAGE_OR_FOLDER",
                   help="image files (PNG, JPEG; truncated or corrupt ones are rejected) or "
                        "folders of them; with --sequence also one video (MP4, AVI, MOV, MKV)")
    p.add_argument("--detector", default="sliding_window", metavar="NAME",
                   help=f"{', '.join(known_detectors())}, or an import path "
                        f"package.module:Class (default: sliding_window)")
    p.add_argument("--camera", help="camera TOML (intrinsics, distortion, height_m, pitch_deg); "
                                     "every image must have its width x height")
    p.add_argument("--config", help="detectors TOML (default: the shipped, tuned one)")
    p.add_argument("--weights", metavar="FILE",
                   help="weights of a learned detector (lanenet; default: the shipped "
                        "detectors/weights/lanenet.pt); checked before anything runs")
    p.add_argument("--format", choices=("json", "tusimple"), default="json",
                   help="tusimple: one {lanes, h_samples, raw_file, run_time} line per image "
                        "(lanenet: every boundary it found, left to right)")
    p.add_argument("--sequence", action="store_true",
                   help="the inputs are one sequence of frames or one video: one detector for "
                        "all frames, its state (LaneNet's memory) kept; one line per frame, "
                        "raw_file a frame's path or VIDEO#N (N from 0)")
    p.add_argument("--overlay", metavar="DIR",
                   help="folder for PNGs with the detected lanes drawn (a sequence: "
                        "NNNNNN_STEM.png in its order; a video: STEM.avi, Motion-JPEG at its "
                        "frame rate)")
    p.set_defaults(func=cmd_detect)

    p = subparsers.add_parser("calibrate", help="chessboard calibration -> camera TOML")
    p.add_argument("images", nargs="+", help="photos of a chessboard")
    p.add_argument("--pattern", default="9x6", help="inner corners, e.g. 9x6")
    p.add_argument("--out", default="camera.toml", help="camera TOML to write")
    p.add_argument("--min-images", type=int, default=5)
    p.add_argument("--height-m", type=float, default=1.5, help="mounting height to record")
    p.set_defaults(func=cmd_calibrate)
