"""`lanekeep detect` (lane detectors on real photos) and `lanekeep calibrate`.

Thin: argument parsing and output; the work is in lanekeep/evaluation/real_frames.py (a detector
on real frames: its camera, its output line, its overlay), lanekeep/realcam/frames.py (photos,
sequences, videos) and lanekeep/realcam/calibration.py. Images are read by
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
pair.
"""

from __future__ import annotations

import argparse
import json
import os
import secrets
import sys
import tempfile
from pathlib import Path

from lanekeep.cli.outputs import folder_problem
from lanekeep.evaluation.real_frames import (  # noqa: F401 - SLOT_COLOURS: public here too
    SEQUENCE_HORIZON_FRAMES,
    SLOT_COLOURS,
    draw_overlay,
)

_overlay = draw_overlay  # its name here before it moved to the library

EXIT_OK, EXIT_FAILURE, EXIT_BAD_INPUT = 0, 1, 2


def _error(command: str, message: str) -> int:
    print(f"lanekeep {command}: error: {message}", file=sys.stderr)
    return EXIT_BAD_INPUT


def _make_output_dir(folder: str) -> str | None:
    """Create `folder` and prove it takes a file; the problem, or None."""
    try:
        Path(folder).mkdir(parents=True, exist_ok=True)
        with tempfile.NamedTemporaryFile(dir=folder, prefix=".lanekeep-probe-"):
            pass
    except OSError as err:
        return f"{folder}: cannot write there: {err.strerror or err}"
    return None


def _temp_beside(path: Path) -> tuple[int, Path]:
    """A new file next to `path` (same folder, so os.replace is atomic), mode 0666 & ~umask."""
    while True:
        tmp = path.parent / f".{path.name}.{secrets.token_hex(4)}.tmp"
        try:
            return os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o666), tmp
        except FileExistsError:
            continue


def _write_atomically(path: Path, data: bytes) -> None:
    """Write `data` to `path` via a temporary file in the same folder and os.replace."""
    fd, tmp = _temp_beside(path)
    try:
        with os.fdopen(fd, "wb") as f:
            f.write(data)
        os.replace(tmp, path)
    finally:
        tmp.unlink(missing_ok=True)


def _overlay_path(folder: str, image: str) -> Path:
    return Path(folder) / (Path(image).stem + ".png")


def _frame_overlay_path(folder: str, index: int, image: str, n_frames: int) -> Path:
    """A sequence's frame overlay: its index first (names sort in the sequence's order), then
    its image's stem, e.g. 000007_1_10.png."""
    width = max(6, len(str(n_frames - 1)))
    return Path(folder) / f"{index:0{width}d}_{Path(image).stem}.png"


def _video_overlay_path(folder: str, video: str) -> Path:
    from lanekeep.realcam.frames import VIDEO_SUFFIX

    return Path(folder) / (Path(video).stem + VIDEO_SUFFIX)


def _overlay_failed(path: Path, err: OSError) -> int:
    print(f"lanekeep detect: error: {path}: cannot write the overlay: "
          f"{getattr(err, 'strerror', None) or err}", file=sys.stderr)
    return EXIT_FAILURE


def _write_png(path: Path, bgr) -> int | None:
    """The overlay image as a PNG at `path` (atomically); an exit code when it failed."""
    import cv2

    ok, encoded = cv2.imencode(".png", bgr)
    try:
        if not ok:
            raise OSError("OpenCV cannot encode the overlay")
        _write_atomically(path, encoded.tobytes())
    except OSError as err:
        return _overlay_failed(path, err)
    return None


def _input_problems(args: argparse.Namespace, camera_file) -> list[str]:
    """Every problem with the inputs and outputs of `detect`, found before anything runs."""
    from lanekeep.realcam.frames import is_video, size_problem
    from lanekeep.realcam.image_io import read_image

    problems = []
    if args.overlay:
        problem = folder_problem(Path(args.overlay))
        if problem:
            problems.append(problem)
    for path in args.images:
        if Path(path).is_file() and is_video(path):
            problems.append(f"{path}: a video; give --sequence to run the detector through its "
                            f"frames (lanekeep detect --sequence {path})")
            continue
        try:
            h, w = read_image(path).shape[:2]
        except ValueError as err:
            if getattr(args, "debug", False):  # `lanekeep --debug`: the exception, traceback
                raise
            problems.append(str(err))
            continue
        too_small = size_problem(path, w, h)
        if too_small:
            problems.append(too_small)
        elif camera_file is not None and (w, h) != (camera_file.width, camera_file.height):
            problems.append(
                f"{path}: image is {w}x{h} but camera file {args.camera} is calibrated for "
                f"{camera_file.width}x{camera_file.height} (calibrate at this size, or give "
                f"images of that size)")
    if args.overlay and not problems:
        # Two inputs with one stem would overwrite each other's overlay; an input inside the
        # overlay folder could be overwritten by its own.
        seen: dict[Path, str] = {}
        for path in args.images:
            target = _overlay_path(args.overlay, path).resolve()
            source = Path(path).resolve()
            if target == source:
                problems.append(f"{path}: its overlay {_overlay_path(args.overlay, path)} "
                                f"would overwrite the image itself")
            elif seen.setdefault(target, str(source)) != str(source):
                problems.append(f"{path}: its overlay {_overlay_path(args.overlay, path)} "
                                f"would overwrite that of {seen[target]}")
    return problems


def _weights_problem(args: argparse.Namespace, config) -> str | None:
    """Why the weights file the detector would load (--weights, else its own) is unusable."""
    from lanekeep.detectors.registry import check_detectors_weights

    try:
        check_detectors_weights([args.detector], config, args.weights)
    except ValueError as err:  # WeightsError: "PATH: why"
        if getattr(args, "debug", False):
            raise
        return str(err)
    return None


def _sequence_problems(args: argparse.Namespace, source, camera_file) -> list[str]:
    """What stops a checked sequence: its size against the camera file, overlays that would
    overwrite an input."""
    from lanekeep.realcam.frames import VideoFrames

    video = isinstance(source, VideoFrames)
    first = source.path if video else source.paths[0]
    w, h = source.size
    if camera_file is not None and (w, h) != (camera_file.width, camera_file.height):
        return [f"{first}: frames are {w}x{h} but camera file {args.camera} is calibrated for "
                f"{camera_file.width}x{camera_file.height} (calibrate at this size, or give "
                f"frames of that size)"]
    if not args.overlay:
        return []
    if video:
        target = _video_overlay_path(args.overlay, source.path)
        if target.resolve() == Path(source.path).resolve():
            return [f"{source.path}: its overlay {target} would overwrite the video itself"]
        return []
    inputs = {Path(path).resolve() for path in source.paths}
    for k, path in enumerate(source.paths):
        target = _frame_overlay_path(args.overlay, k, path, len(source.paths))
        if target.resolve() in inputs:
            return [f"{path}: its overlay {target} would overwrite an image of the sequence"]
    return []


def _detect_sequence(args: argparse.Namespace, config, camera_file) -> int:
    """`detect --sequence`: one detector through the frames or the video, one line a frame."""
    from lanekeep.evaluation.real_frames import sequence_detector
    from lanekeep.realcam.frames import VideoFrames, VideoOut, open_sequence
    from lanekeep.realcam.image_io import ImageError

    problems = []
    if args.overlay:
        problem = folder_problem(Path(args.overlay))
        problems += [problem] if problem else []
    source, found = open_sequence(args.images)
    problems += found
    if source is not None:
        problems += _sequence_problems(args, source, camera_file)
    if _refused(args, config, problems):
        return EXIT_BAD_INPUT
    try:  # one camera and one detector for every frame
        detect = sequence_detector(source.frames(), args.detector, config, camera_file,
                                   args.weights)
    except ValueError as err:  # a frame or the weights file changed since it was checked
        if getattr(args, "debug", False):
            raise
        return _error("detect", str(err))
    video = isinstance(source, VideoFrames)
    n_frames = None if video else len(source.paths)
    target = _video_overlay_path(args.overlay, source.path) if args.overlay and video else None
    out = None
    if target is not None:
        try:
            out = VideoOut(target, source.fps, source.size)
        except OSError as err:
            return _overlay_failed(target, err)
    try:
        for frame in source.frames():
            result = detect(frame.image)
            print(json.dumps(result.line(frame.label, args.format)), flush=True)
            if out is not None:
                out.write(result.overlay(frame.image))
            elif args.overlay:
                png = _frame_overlay_path(args.overlay, frame.index, frame.label, n_frames)
                failed = _write_png(png, result.overlay(frame.image))
                if failed:
                    return failed
    except BaseException as err:
        if out is not None:  # no half-written video left behind
            out.abort()
        if isinstance(err, ImageError):  # a frame changed since it was checked
            return _error("detect", str(err))
        raise
    if out is not None:
        try:
            out.close()
        except OSError as err:
            return _overlay_failed(target, err)
    return EXIT_OK


def _refused(args: argparse.Namespace, config, problems: list[str]) -> bool:
    """The input problems found, the weights file's added, each printed as one error line;
    True when there is any. Without one, the overlay folder is made (nothing before)."""
    weights_problem = _weights_problem(args, config)
    problems = [*problems, *([weights_problem] if weights_problem else [])]
    if not problems and args.overlay:
        problem = _make_output_dir(args.overlay)
        problems += [problem] if problem else []
    for problem in problems:
        _error("detect", problem)
    return bool(problems)


def cmd_detect(args: argparse.Namespace) -> int:
    from lanekeep.detectors.config import load_config
    from lanekeep.evaluation.real_frames import frame_detector
    from lanekeep.realcam.camera_file import read_camera_file
    from lanekeep.realcam.frames import expand_folders
    from lanekeep.realcam.image_io import read_image

    try:
        config = load_config(args.config)
        camera_file = read_camera_file(args.camera) if args.camera else None
    except (OSError, ValueError) as err:
        if getattr(args, "debug", False):
            raise
        if isinstance(err, OSError) and err.filename:
            return _error("detect", f"{err.filename}: cannot read it: {err.strerror or err}")
        return _error("detect", str(err))
    if args.sequence:
        return _detect_sequence(args, config, camera_file)
    # All inputs first: a bad one stops the command before any detection or output.
    args.images, problems = expand_folders(args.images)
    problems += _input_problems(args, camera_file)
    if _refused(args, config, problems):
        return EXIT_BAD_INPUT
    for path in args.images:
        try:
            image = read_image(path)  # checked above; changed since, it is still an error
        except ValueError as err:
            return _error("detect", str(err))
        try:  # a new camera and detector per photo: a learned one's memory would mislead
            detect = frame_detector([image], args.detector, config, camera_file, args.weights)
        except ValueError as err:  # the weights file changed since it was checked
            if getattr(args, "debug", False):
                raise
            return _error("detect", str(err))
        result = detect(image)
        print(json.dumps(result.line(str(path), args.format)), flush=True)
        if args.overlay:
            failed = _write_png(_overlay_path(args.overlay, path), result.overlay(image))
            if failed:
                return failed
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
        fd, tmp = _temp_beside(out)
        os.close(fd)
        try:
            write_camera_file(tmp, cam, comment=(
                f"lanekeep calibrate: {len(result.used)} images, pattern {args.pattern}, "
                f"reprojection RMS {result.rms_px:.3f} px"))
            os.replace(tmp, out)
        finally:
            tmp.unlink(missing_ok=True)
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
                    "vanishing point (detectors.toml [dashcam]). A folder stands for its "
                    "images (PNG, JPEG, BMP, TIFF, WebP; not its subfolders) in sorted order. "
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
