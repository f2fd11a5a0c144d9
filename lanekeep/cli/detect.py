"""`lanekeep detect` (lane detectors on real photos) and `lanekeep calibrate`.

Thin: argument parsing and output; the work is in detectors/ and lanekeep/realcam/calibration.py.
Images are read by lanekeep/realcam/image_io.py, which rejects missing, empty, truncated and corrupt
files. `detect` checks every input (and the overlay folder) before it runs anything: one bad input
and nothing is detected or written.
Exit codes: 0 success, 1 a failure while running (an overlay that could not be written),
2 bad input (a missing, empty, truncated, corrupt or wrongly sized image, an output folder that
cannot be written, a weights file that is missing, empty, corrupt or of another architecture, too
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
import time
from pathlib import Path

from lanekeep.cli.outputs import folder_problem

EXIT_OK, EXIT_FAILURE, EXIT_BAD_INPUT = 0, 1, 2
MIN_IMAGE_PX = 64
# What a folder given to `detect` contributes: its files with these suffixes (any case).
IMAGE_SUFFIXES = (".png", ".jpg", ".jpeg", ".bmp", ".tif", ".tiff", ".webp")


def _error(command: str, message: str) -> int:
    print(f"lanekeep {command}: error: {message}", file=sys.stderr)
    return EXIT_BAD_INPUT


# Overlay colours (BGR): the ego pair green / red, the next boundaries orange / magenta, the
# "other" ones (up to three) cyan, blue and pink; unnamed lanes (classical) alternate as before.
SLOT_COLOURS = {"ego-left": (0, 255, 0), "ego-right": (0, 0, 255), "next-left": (0, 165, 255),
                "next-right": (255, 0, 255)}
OTHER_COLOURS = [(255, 255, 0), (255, 128, 0), (180, 130, 255)]
UNNAMED_COLOURS = [(0, 255, 0), (255, 0, 0)]


def _lane_colour(name: str | None, k: int, n_other: int) -> tuple[int, int, int]:
    if name is None:
        return UNNAMED_COLOURS[k % 2]
    return SLOT_COLOURS.get(name, OTHER_COLOURS[n_other % len(OTHER_COLOURS)])


def _overlay(image, estimate, lanes: list[tuple[str | None, list[int]]], h_samples,
             horizon: float, verdict=None):
    """The image with each lane (name or None, x per h_sample) drawn, named at its bottom."""
    import cv2

    out = image[..., ::-1].copy()
    n_other, labels = 0, []
    for k, (name, xs) in enumerate(lanes):
        colour = _lane_colour(name, k, n_other)
        n_other += name is not None and name not in SLOT_COLOURS
        pts = [(x, v) for x, v in zip(xs, h_samples, strict=True) if x >= 0]
        for a, b in zip(pts, pts[1:], strict=False):
            cv2.line(out, a, b, colour, 3)
        if name is not None and pts:
            x, v = pts[-1]  # the lowest row it reaches
            x, v = min(max(x - 40, 5), out.shape[1] - 140), max(v - 12, 20)
            while any(abs(x - lx) < 130 and abs(v - lv) < 26 for lx, lv in labels):
                v -= 26  # above a neighbour's name rather than over it
            labels.append((x, v))
            cv2.putText(out, name, (x, v), cv2.FONT_HERSHEY_SIMPLEX, 0.8, colour, 2)
    cv2.line(out, (0, int(horizon)), (out.shape[1] - 1, int(horizon)), (0, 255, 255), 1)
    text = (f"offset {estimate.offset_m:+.2f} m at x={estimate.x_m:.1f} m" if estimate.valid
            else f"no lane: {estimate.reason}")
    cv2.putText(out, text, (20, 40), cv2.FONT_HERSHEY_SIMPLEX, 1.0, (255, 255, 255), 2)
    if verdict is not None and estimate.valid:  # the geometry's word on it (plausibility)
        words = "plausible" if verdict.valid else "implausible"
        note = f"{words}, confidence {verdict.confidence:.2f}"
        for k, line in enumerate([note, *verdict.reasons[:3]]):
            cv2.putText(out, line, (20, 80 + 34 * k), cv2.FONT_HERSHEY_SIMPLEX, 0.8,
                        (0, 255, 255) if verdict.valid else (0, 0, 255), 2)
    return out


def _plausibility(estimate, detector, image, camera, config):
    """Whether the detection looks like a lane (detectors/plausibility.py): reporting only,
    the detection itself is unchanged."""
    from lanekeep.detectors.plausibility import check, support_share, vehicle_cover

    window = detector.window
    covered = vehicle_cover(image, camera, config.preprocess) if estimate.valid else None
    return check(estimate, (window.x_near_m, window.x_far_m),
                 support_share(estimate, covered))


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


def expand_folders(paths: list[str]) -> tuple[list[str], list[str]]:
    """(images, problems): each folder in `paths` replaced by its images (IMAGE_SUFFIXES, not
    hidden, not in subfolders) sorted by name; a folder with none is a problem."""
    images, problems = [], []
    for path in paths:
        if not Path(path).is_dir():
            images.append(path)
            continue
        found = sorted(str(p) for p in Path(path).iterdir()
                       if p.is_file() and not p.name.startswith(".")
                       and p.suffix.lower() in IMAGE_SUFFIXES)
        if not found:
            problems.append(f"{path}: a folder with no images in it "
                            f"({', '.join(IMAGE_SUFFIXES)})")
        images.extend(found)
    return images, problems


def _input_problems(args: argparse.Namespace, camera_file) -> list[str]:
    """Every problem with the inputs and outputs of `detect`, found before anything runs."""
    from lanekeep.realcam.image_io import read_image

    problems = []
    if args.overlay:
        problem = folder_problem(Path(args.overlay))
        if problem:
            problems.append(problem)
    for path in args.images:
        try:
            h, w = read_image(path).shape[:2]
        except ValueError as err:
            if getattr(args, "debug", False):  # `lanekeep --debug`: the exception, traceback
                raise
            problems.append(str(err))
            continue
        if h < MIN_IMAGE_PX or w < MIN_IMAGE_PX:
            problems.append(f"{path}: image is {w}x{h}, too small for lane detection "
                            f"(at least {MIN_IMAGE_PX}x{MIN_IMAGE_PX})")
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


def cmd_detect(args: argparse.Namespace) -> int:
    import cv2

    from lanekeep.detectors.config import load_config
    from lanekeep.detectors.registry import make_detector
    from lanekeep.detectors.tusimple import estimate_lanes, every_lane, h_samples_for, record
    from lanekeep.realcam.camera_file import camera_for_image, read_camera_file
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
    dash = config.dashcam
    # All inputs first: a bad one stops the command before any detection or output.
    args.images, problems = expand_folders(args.images)
    problems += _input_problems(args, camera_file)
    weights_problem = _weights_problem(args, config)
    problems += [weights_problem] if weights_problem else []
    if not problems and args.overlay:
        problem = _make_output_dir(args.overlay)
        problems += [problem] if problem else []
    if problems:
        for problem in problems:
            _error("detect", problem)
        return EXIT_BAD_INPUT
    for path in args.images:
        try:
            image = read_image(path)  # checked above; changed since, it is still an error
        except ValueError as err:
            return _error("detect", str(err))
        h, w = image.shape[:2]
        camera, cam_file, horizon = camera_for_image(
            image, camera_file, dash.hfov_deg, dash.height_m, dash.horizon_fraction,
            dash.min_horizon_fraction, dash.max_horizon_fraction)
        distortion = None if camera_file is None else cam_file.distortion
        try:  # a new detector per photo: a learned one's memory of another photo would mislead
            detector = make_detector(args.detector, camera, config, distortion, args.weights)
        except ValueError as err:  # the weights file changed since it was checked
            if getattr(args, "debug", False):
                raise
            return _error("detect", str(err))
        start = time.perf_counter()
        estimate = detector.detect(image)
        ms = (time.perf_counter() - start) * 1000.0
        verdict = _plausibility(estimate, detector, image, camera, config)
        h_samples = h_samples_for(h)
        # Detectors that see every boundary keep them with the frame's other outputs.
        named = every_lane(detector, camera, camera_file is not None, h_samples, (w, h), horizon)
        if named is not None:
            lanes = [lane.xs for lane in named]
            drawn = [(lane.name, lane.xs) for lane in named]
        else:
            window = detector.window
            x_range = (float(camera.position_m[0]) + 1.0, window.x_far_m * 1.3)
            lanes = estimate_lanes(estimate, camera, h_samples, x_range)
            drawn = [(None, xs) for xs in lanes]
        if args.format == "tusimple":
            line = record(str(path), lanes, h_samples, ms)
        else:
            line = {
                "raw_file": str(path), **verdict.to_dict(),
                "detector_valid": estimate.valid, "detector_confidence": estimate.confidence,
                "offset_m": estimate.offset_m, "x_m": estimate.x_m,
                "left": None if estimate.left is None else [float(c) for c in estimate.left],
                "right": None if estimate.right is None else [float(c) for c in estimate.right],
                "reason": estimate.reason,
                "horizon_row": horizon, "run_time_ms": round(ms, 2),
            }
            if named is not None:
                line["h_samples"] = list(h_samples)
                line["boundaries"] = [{"slot": lane.name, "xs": lane.xs,
                                       "score": round(lane.score, 4)} for lane in named]
        print(json.dumps(line), flush=True)
        if args.overlay:
            png = _overlay_path(args.overlay, path)
            ok, encoded = cv2.imencode(
                ".png", _overlay(image, estimate, drawn, h_samples, horizon, verdict))
            try:
                if not ok:
                    raise OSError("OpenCV cannot encode the overlay")
                _write_atomically(png, encoded.tobytes())
            except OSError as err:
                print(f"lanekeep detect: error: {png}: cannot write the overlay: "
                      f"{getattr(err, 'strerror', None) or err}", file=sys.stderr)
                return EXIT_FAILURE
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
                    "nothing is detected or written, and the exit code is 2.")
    p.add_argument("images", nargs="+", metavar="IMAGE_OR_FOLDER",
                   help="image files (PNG, JPEG; truncated or corrupt ones are rejected) or "
                        "folders of them")
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
    p.add_argument("--overlay", help="folder for PNGs with the detected lanes drawn")
    p.set_defaults(func=cmd_detect)

    p = subparsers.add_parser("calibrate", help="chessboard calibration -> camera TOML")
    p.add_argument("images", nargs="+", help="photos of a chessboard")
    p.add_argument("--pattern", default="9x6", help="inner corners, e.g. 9x6")
    p.add_argument("--out", default="camera.toml", help="camera TOML to write")
    p.add_argument("--min-images", type=int, default=5)
    p.add_argument("--height-m", type=float, default=1.5, help="mounting height to record")
    p.set_defaults(func=cmd_calibrate)
