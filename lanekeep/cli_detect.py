"""`lanekeep detect` (classical detectors on real photos) and `lanekeep calibrate`.

Thin: argument parsing and output; the work is in detectors/ and lanekeep/calibration.py.
Exit codes: 0 success, 2 bad input (missing or unreadable image, too few chessboards).
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

EXIT_OK, EXIT_BAD_INPUT = 0, 2
MIN_IMAGE_PX = 64


def _error(command: str, message: str) -> int:
    print(f"lanekeep {command}: error: {message}", file=sys.stderr)
    return EXIT_BAD_INPUT


def _overlay(image, camera, estimate, lanes, h_samples, horizon: float):
    import cv2

    out = image[..., ::-1].copy()
    colours = [(0, 255, 0), (255, 0, 0)]
    for k, xs in enumerate(lanes):
        pts = [(x, v) for x, v in zip(xs, h_samples, strict=True) if x >= 0]
        for a, b in zip(pts, pts[1:], strict=False):
            cv2.line(out, a, b, colours[k % 2], 3)
    cv2.line(out, (0, int(horizon)), (out.shape[1] - 1, int(horizon)), (0, 255, 255), 1)
    text = (f"offset {estimate.offset_m:+.2f} m at x={estimate.x_m:.1f} m" if estimate.valid
            else f"no lane: {estimate.reason}")
    cv2.putText(out, text, (20, 40), cv2.FONT_HERSHEY_SIMPLEX, 1.0, (255, 255, 255), 2)
    return out


def cmd_detect(args: argparse.Namespace) -> int:
    import cv2

    from detectors.config import load_config
    from detectors.registry import make_detector
    from detectors.tusimple import estimate_lanes, h_samples_for, record
    from lanekeep.calibration import read_image
    from lanekeep.camera_file import camera_for_image, read_camera_file

    try:
        config = load_config(args.config)
        camera_file = read_camera_file(args.camera) if args.camera else None
    except (OSError, ValueError) as err:
        return _error("detect", str(err))
    dash = config.dashcam
    if args.overlay:
        Path(args.overlay).mkdir(parents=True, exist_ok=True)
    for path in args.images:
        try:
            image = read_image(path)
        except ValueError as err:
            return _error("detect", str(err))
        h, w = image.shape[:2]
        if h < MIN_IMAGE_PX or w < MIN_IMAGE_PX:
            return _error("detect", f"{path}: image is {w}x{h}, too small for lane detection "
                                    f"(at least {MIN_IMAGE_PX}x{MIN_IMAGE_PX})")
        camera, cam_file, horizon = camera_for_image(
            image, camera_file, dash.hfov_deg, dash.height_m, dash.horizon_fraction,
            dash.min_horizon_fraction, dash.max_horizon_fraction)
        distortion = None if camera_file is None else cam_file.distortion
        detector = make_detector(args.detector, camera, config, distortion)
        start = time.perf_counter()
        estimate = detector.detect(image)
        ms = (time.perf_counter() - start) * 1000.0
        h_samples = h_samples_for(h)
        window = detector.window
        x_range = (float(camera.position_m[0]) + 1.0, window.x_far_m * 1.3)
        lanes = estimate_lanes(estimate, camera, h_samples, x_range)
        if args.format == "tusimple":
            line = record(str(path), lanes, h_samples, ms)
        else:
            line = {
                "raw_file": str(path), "valid": estimate.valid,
                "offset_m": estimate.offset_m, "x_m": estimate.x_m,
                "left": None if estimate.left is None else [float(c) for c in estimate.left],
                "right": None if estimate.right is None else [float(c) for c in estimate.right],
                "confidence": estimate.confidence, "reason": estimate.reason,
                "horizon_row": horizon, "run_time_ms": round(ms, 2),
            }
        print(json.dumps(line))
        if args.overlay:
            png = Path(args.overlay) / (Path(path).stem + ".png")
            cv2.imwrite(str(png), _overlay(image, camera, estimate, lanes, h_samples, horizon))
    return EXIT_OK


def cmd_calibrate(args: argparse.Namespace) -> int:
    from lanekeep.calibration import CalibrationError, calibrate, parse_pattern, read_image
    from lanekeep.camera_file import write_camera_file

    try:
        pattern = parse_pattern(args.pattern)
    except ValueError as err:
        return _error("calibrate", str(err))
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
    write_camera_file(args.out, cam, comment=(
        f"lanekeep calibrate: {len(result.used)} images, pattern {args.pattern}, "
        f"reprojection RMS {result.rms_px:.3f} px"))
    print(f"reprojection RMS {result.rms_px:.3f} px over {len(result.used)} images")
    print(f"fx {cam.fx:.2f} fy {cam.fy:.2f} cx {cam.cx:.2f} cy {cam.cy:.2f} "
          f"distortion {', '.join(f'{d:.4g}' for d in cam.distortion)}")
    for name, why in unreadable + result.rejected:
        print(f"not used: {name}: {why}")
    print(f"wrote {args.out}")
    return EXIT_OK


def register(subparsers) -> None:
    """Add the `detect` and `calibrate` subcommands (each sets func(args) -> exit code)."""
    from detectors.registry import known_detectors

    p = subparsers.add_parser(
        "detect", help="run a classical lane detector on real road photos",
        description="Without --camera the camera is an unknown 1.5 m high dashcam with a "
                    "60 deg horizontal field of view whose pitch is taken from each image's "
                    "vanishing point (detectors.toml [dashcam]).")
    p.add_argument("images", nargs="+", help="image files (PNG, JPEG)")
    p.add_argument("--detector", choices=known_detectors(), default="sliding_window")
    p.add_argument("--camera", help="camera TOML (intrinsics, distortion, height_m, pitch_deg)")
    p.add_argument("--config", help="detectors TOML (default: the shipped, tuned one)")
    p.add_argument("--format", choices=("json", "tusimple"), default="json")
    p.add_argument("--overlay", help="folder for PNGs with the detected lanes drawn")
    p.set_defaults(func=cmd_detect)

    p = subparsers.add_parser("calibrate", help="chessboard calibration -> camera TOML")
    p.add_argument("images", nargs="+", help="photos of a chessboard")
    p.add_argument("--pattern", default="9x6", help="inner corners, e.g. 9x6")
    p.add_argument("--out", default="camera.toml", help="camera TOML to write")
    p.add_argument("--min-images", type=int, default=5)
    p.add_argument("--height-m", type=float, default=1.5, help="mounting height to record")
    p.set_defaults(func=cmd_calibrate)
