"""`lanekeep detect` as a library: photos or one sequence through a detector, every input
checked first, one output line a frame, overlays written atomically.

The checks come before anything runs (`photo_problems`, `sequence_problems`, `refusals`): one
bad input and nothing is detected or written, each problem one line. The runs
(`detect_photos`, `detect_sequence`) hand each frame's output line to `emit` as it is made and
stop at the first overlay that cannot be written (`OverlayError`) or input that changed since
its check (`InputChanged`). A photo gets a new camera and detector; a sequence one of each for
all its frames (lanekeep/evaluation/real_frames.py says why).
"""

from __future__ import annotations

import tempfile
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from lanekeep.core.files import atomic_write, folder_problem

if TYPE_CHECKING:
    from lanekeep.detectors.config import DetectorsConfig
    from lanekeep.realcam.camera_file import CameraFile
    from lanekeep.realcam.frames import FrameSource

Emit = Callable[[dict], None]


class OverlayError(OSError):
    """An overlay that could not be written (the run stops; exit 1)."""

    def __init__(self, path: Path, cause: OSError) -> None:
        super().__init__(f"{path}: cannot write the overlay: "
                         f"{getattr(cause, 'strerror', None) or cause}")
        self.path, self.cause = path, cause


class InputChanged(ValueError):
    """An input that passed its check but could not be read when its turn came."""


class DetectorUnavailable(ValueError):
    """The detector could not be made (its weights file changed since it was checked); the
    cause is the original error."""


@dataclass(frozen=True)
class DetectRequest:
    """What `detect` runs: the detector and its settings, the camera, the outputs."""

    detector: str
    config: DetectorsConfig
    camera_file: CameraFile | None = None
    camera_name: str | None = None  # the camera file as the user named it (for messages)
    weights: str | None = None
    format: str = "json"  # or "tusimple"
    overlay: str | None = None  # folder for overlays
    strict: bool = False  # raise a problem's exception instead of reporting it (--debug)


# -- where the overlays go ---------------------------------------------------------------------
def overlay_path(folder: str, image: str) -> Path:
    return Path(folder) / (Path(image).stem + ".png")


def frame_overlay_path(folder: str, index: int, image: str, n_frames: int) -> Path:
    """A sequence's frame overlay: its index first (names sort in the sequence's order), then
    its image's stem, e.g. 000007_1_10.png."""
    width = max(6, len(str(n_frames - 1)))
    return Path(folder) / f"{index:0{width}d}_{Path(image).stem}.png"


def video_overlay_path(folder: str, video: str) -> Path:
    from lanekeep.realcam.frames import VIDEO_SUFFIX

    return Path(folder) / (Path(video).stem + VIDEO_SUFFIX)


def write_png(path: Path, bgr: np.ndarray) -> None:
    """The overlay image as a PNG at `path` (atomically); OverlayError when it failed."""
    import cv2

    ok, encoded = cv2.imencode(".png", bgr)
    try:
        if not ok:
            raise OSError("OpenCV cannot encode the overlay")
        atomic_write(path, encoded.tobytes(), sync=False)
    except OSError as err:
        raise OverlayError(path, err) from err


# -- the checks before anything runs -----------------------------------------------------------
def _camera_mismatch(request: DetectRequest, label: str, size: tuple[int, int],
                     what: str) -> str | None:
    cam = request.camera_file
    if cam is None or size == (cam.width, cam.height):
        return None
    return (f"{label}: {what} {size[0]}x{size[1]} but camera file {request.camera_name} is "
            f"calibrated for {cam.width}x{cam.height} (calibrate at this size, or give "
            f"{'images' if what == 'image is' else 'frames'} of that size)")


def photo_problems(request: DetectRequest, images: Sequence[str]) -> list[str]:
    """Every problem with the photos and the overlay folder, found before anything runs."""
    from lanekeep.realcam.frames import is_video, size_problem
    from lanekeep.realcam.image_io import read_image

    problems = []
    if request.overlay:
        problem = folder_problem(Path(request.overlay))
        if problem:
            problems.append(problem)
    for path in images:
        if Path(path).is_file() and is_video(path):
            problems.append(f"{path}: a video; give --sequence to run the detector through its "
                            f"frames (lanekeep detect --sequence {path})")
            continue
        try:
            h, w = read_image(path).shape[:2]
        except ValueError as err:
            if request.strict:
                raise
            problems.append(str(err))
            continue
        too_small = size_problem(path, w, h)
        if too_small:
            problems.append(too_small)
        else:
            mismatch = _camera_mismatch(request, path, (w, h), "image is")
            problems += [mismatch] if mismatch else []
    if request.overlay and not problems:
        problems += _overlay_collisions(request.overlay, images)
    return problems


def _overlay_collisions(folder: str, images: Sequence[str]) -> list[str]:
    """Two inputs with one stem would overwrite each other's overlay; an input inside the
    overlay folder could be overwritten by its own."""
    problems = []
    seen: dict[Path, str] = {}
    for path in images:
        target = overlay_path(folder, path).resolve()
        source = Path(path).resolve()
        if target == source:
            problems.append(f"{path}: its overlay {overlay_path(folder, path)} "
                            f"would overwrite the image itself")
        elif seen.setdefault(target, str(source)) != str(source):
            problems.append(f"{path}: its overlay {overlay_path(folder, path)} "
                            f"would overwrite that of {seen[target]}")
    return problems


def sequence_problems(request: DetectRequest, inputs: Sequence[str]
                      ) -> tuple[FrameSource | None, list[str]]:
    """The sequence the inputs make and every problem with it and the overlay folder: its
    frames (lanekeep/realcam/frames.py), its size against the camera file, overlays that
    would overwrite an input."""
    from lanekeep.realcam.frames import open_sequence

    problems = []
    if request.overlay:
        problem = folder_problem(Path(request.overlay))
        problems += [problem] if problem else []
    source, found = open_sequence(inputs)
    problems += found
    if source is not None:
        problems += _checked_sequence_problems(request, source)
    return source, problems


def _checked_sequence_problems(request: DetectRequest, source: FrameSource) -> list[str]:
    from lanekeep.realcam.frames import VideoFrames

    video = isinstance(source, VideoFrames)
    first = source.path if video else source.paths[0]
    mismatch = _camera_mismatch(request, first, source.size, "frames are")
    if mismatch:
        return [mismatch]
    if not request.overlay:
        return []
    if video:
        target = video_overlay_path(request.overlay, source.path)
        if target.resolve() == Path(source.path).resolve():
            return [f"{source.path}: its overlay {target} would overwrite the video itself"]
        return []
    inputs = {Path(path).resolve() for path in source.paths}
    for k, path in enumerate(source.paths):
        target = frame_overlay_path(request.overlay, k, path, len(source.paths))
        if target.resolve() in inputs:
            return [f"{path}: its overlay {target} would overwrite an image of the sequence"]
    return []


def _make_output_dir(folder: str) -> str | None:
    """Create `folder` and prove it takes a file; the problem, or None."""
    try:
        Path(folder).mkdir(parents=True, exist_ok=True)
        with tempfile.NamedTemporaryFile(dir=folder, prefix=".lanekeep-probe-"):
            pass
    except OSError as err:
        return f"{folder}: cannot write there: {err.strerror or err}"
    return None


def refusals(request: DetectRequest, problems: list[str]) -> list[str]:
    """The input problems found with the weights file's added; without any, the overlay
    folder is made (nothing before), and a folder that will not take a file is one."""
    from lanekeep.detectors.registry import check_detectors_weights

    problems = list(problems)
    try:
        check_detectors_weights([request.detector], request.config, request.weights)
    except ValueError as err:  # WeightsError: "PATH: why"
        if request.strict:
            raise
        problems.append(str(err))
    if not problems and request.overlay:
        problem = _make_output_dir(request.overlay)
        problems += [problem] if problem else []
    return problems


# -- the runs ----------------------------------------------------------------------------------
def detect_photos(request: DetectRequest, images: Sequence[str], emit: Emit) -> None:
    """Each photo (checked) through a new camera and detector, its line to `emit`, its
    overlay written. InputChanged for a photo that changed since its check, OverlayError for
    an overlay not written, DetectorUnavailable when the detector cannot be made."""
    from lanekeep.evaluation.real_frames import frame_detector
    from lanekeep.realcam.image_io import read_image

    for path in images:
        try:
            image = read_image(path)  # checked; changed since, it is still an error
        except ValueError as err:
            raise InputChanged(str(err)) from err
        try:  # a new camera and detector per photo: a learned one's memory would mislead
            detect = frame_detector([image], request.detector, request.config,
                                    request.camera_file, request.weights)
        except ValueError as err:
            raise DetectorUnavailable(str(err)) from err
        result = detect(image)
        emit(result.line(str(path), request.format))
        if request.overlay:
            write_png(overlay_path(request.overlay, path), result.overlay(image))


def detect_sequence(request: DetectRequest, source: FrameSource, emit: Emit) -> None:
    """One detector (state kept) through a checked sequence's frames, a line each to `emit`;
    overlays as PNGs, or one video for a video (nothing of it left when the run fails).
    Raises as `detect_photos`."""
    from lanekeep.evaluation.real_frames import sequence_detector
    from lanekeep.realcam.frames import VideoFrames, VideoOut
    from lanekeep.realcam.image_io import ImageError

    try:  # one camera and one detector for every frame
        detect = sequence_detector(source.frames(), request.detector, request.config,
                                   request.camera_file, request.weights)
    except ValueError as err:  # a frame or the weights file changed since it was checked
        raise DetectorUnavailable(str(err)) from err
    video = isinstance(source, VideoFrames)
    n_frames = None if video else len(source.paths)
    folder = request.overlay
    target = video_overlay_path(folder, source.path) if folder and video else None
    out = None
    if target is not None:
        try:
            out = VideoOut(target, source.fps, source.size)
        except OSError as err:
            raise OverlayError(target, err) from err
    try:
        for frame in source.frames():
            result = detect(frame.image)
            emit(result.line(frame.label, request.format))
            if out is not None:
                out.write(result.overlay(frame.image))
            elif folder:
                png = frame_overlay_path(folder, frame.index, frame.label, n_frames)
                write_png(png, result.overlay(frame.image))
    except BaseException as err:
        if out is not None:  # no half-written video left behind
            out.abort()
        if isinstance(err, ImageError):  # a frame changed since it was checked
            raise InputChanged(str(err)) from err
        raise
    if out is not None:
        try:
            out.close()
        except OSError as err:
            raise OverlayError(target, err) from err
