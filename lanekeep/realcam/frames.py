"""Frames for `lanekeep detect`: photos, a sequence of frames, or a video, checked before use.

A sequence is either image files (in the order given; a folder stands for its images in natural
order, `1_4` before `1_10`) or one video file that OpenCV's reader opens (FFmpeg in the pip
wheel: MP4, AVI, MOV, MKV, ...). Each frame carries a label, what `detect` prints as
`raw_file`: an image's path as given, or for a video `PATH#N`, PATH as given and N the frame's
index counted from 0.

`open_sequence` checks a sequence before any frame is used: every image readable (image_io's
strict checks) and large enough, all of one size (else one problem naming the first frame of
another size); a video that opens and whose first frame decodes. A video is not decoded to its
end by the check: it ends where OpenCV's reader stops (its last frame, or the first one it cannot
decode). FFmpeg's messages on fd 2 are captured (image_io.call_quietly), never shown.

`VideoOut` writes an annotated video atomically: Motion-JPEG in AVI, every frame its own JPEG
(thin drawn lines stay sharp, the frame count is exact), at the input's frame rate, through the
FFmpeg backend (fractional rates such as 29.97 kept); read back by the same wheel.
"""

from __future__ import annotations

import math
import re
from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path, PurePath

import cv2
import numpy as np

from lanekeep.core.files import PendingFile
from lanekeep.realcam.image_io import JPEG_SOI, PNG_SIGNATURE, ImageError, call_quietly, read_image

MIN_IMAGE_PX = 64  # below this, in either direction, there is no lane to detect
# What a folder contributes: its files with these suffixes (any case), not hidden ones.
IMAGE_SUFFIXES = (".png", ".jpg", ".jpeg", ".bmp", ".tif", ".tiff", ".webp")
# Taken as videos by their suffix (any case); a file of another suffix that is no image but
# opens in OpenCV's reader is one too.
VIDEO_SUFFIXES = (".mp4", ".avi", ".mov", ".mkv")
VIDEO_FOURCC, VIDEO_SUFFIX = "MJPG", ".avi"  # annotated videos: Motion-JPEG in AVI
DEFAULT_FPS = 30.0  # for a video whose file does not state its rate
_DIGITS = re.compile(r"(\d+)")


def natural_key(name: str) -> tuple[list[int | str], str, str]:
    """Sort key comparing runs of digits as numbers (`1_4` before `1_10`, `frame2` before
    `frame10`), the rest case-blind, the stem before the suffix (`frame.png` before
    `frame2.png`); the name itself breaks ties (`a01` vs `a1`)."""
    path = PurePath(name)
    parts = _DIGITS.split(path.stem)  # text, number, text, ...: like positions, like types
    return ([int(p) if k % 2 else p.lower() for k, p in enumerate(parts)], path.suffix.lower(),
            name)


def folder_images(folder: str | Path, natural: bool = False) -> list[str]:
    """The images of `folder` (IMAGE_SUFFIXES, not hidden, not in subfolders), sorted by name:
    naturally (`natural_key`) or as strings (photo mode's order since its first version)."""
    found = [p for p in Path(folder).iterdir()
             if p.is_file() and not p.name.startswith(".") and p.suffix.lower() in IMAGE_SUFFIXES]
    if natural:
        return [str(p) for p in sorted(found, key=lambda p: natural_key(p.name))]
    return sorted(str(p) for p in found)


def expand_folders(paths: Sequence[str], natural: bool = False) -> tuple[list[str], list[str]]:
    """(images, problems): each folder in `paths` replaced by its images (`folder_images`);
    a folder with none is a problem."""
    images, problems = [], []
    for path in paths:
        if not Path(path).is_dir():
            images.append(path)
            continue
        found = folder_images(path, natural)
        if not found:
            problems.append(f"{path}: a folder with no images in it "
                            f"({', '.join(IMAGE_SUFFIXES)})")
        images.extend(found)
    return images, problems


def size_problem(label: str, width: int, height: int) -> str | None:
    if width < MIN_IMAGE_PX or height < MIN_IMAGE_PX:
        return (f"{label}: image is {width}x{height}, too small for lane detection "
                f"(at least {MIN_IMAGE_PX}x{MIN_IMAGE_PX})")
    return None


def _open_capture(path: str) -> cv2.VideoCapture | None:
    """OpenCV's reader on `path` (FFmpeg's complaints captured), or None when it cannot open."""
    capture, _ = call_quietly(cv2.VideoCapture, str(path))
    if capture.isOpened():
        return capture
    capture.release()
    return None


def _read(capture: cv2.VideoCapture) -> np.ndarray | None:
    """The next frame (BGR), or None at the end or at a frame that cannot be decoded."""
    (ok, frame), _ = call_quietly(capture.read)
    return frame if ok and frame is not None else None


def is_video(path: str | Path) -> bool:
    """Whether `path` is a video: a VIDEO_SUFFIXES file, or a file of no image suffix and no
    JPEG or PNG signature whose first frame OpenCV's reader decodes."""
    p = Path(path)
    suffix = p.suffix.lower()
    if suffix in VIDEO_SUFFIXES:
        return True
    if suffix in IMAGE_SUFFIXES or not p.is_file():
        return False
    try:
        with p.open("rb") as f:
            head = f.read(len(PNG_SIGNATURE))
    except OSError:
        return False
    if not head or head.startswith((JPEG_SOI, PNG_SIGNATURE)):
        return False
    capture = _open_capture(str(p))
    if capture is None:
        return False
    try:
        return _read(capture) is not None
    finally:
        capture.release()


@dataclass(frozen=True)
class Frame:
    """One frame of a sequence: its index from 0, its label (`raw_file`) and its RGB pixels."""

    index: int
    label: str
    image: np.ndarray


@dataclass(frozen=True)
class ImageSequence:
    """Image files read in order; `size` (width, height) is every one's, checked."""

    paths: tuple[str, ...]
    size: tuple[int, int]
    fps: float | None = None  # photos have no frame rate

    def frames(self) -> Iterator[Frame]:
        """Each image read again (ImageError if it changed since the check)."""
        for k, path in enumerate(self.paths):
            image = read_image(path)
            if image.shape[1::-1] != self.size:
                h, w = image.shape[:2]
                raise ImageError(path, f"frame is {w}x{h}, no longer the sequence's "
                                       f"{self.size[0]}x{self.size[1]}")
            yield Frame(k, str(path), image)


@dataclass(frozen=True)
class VideoFrames:
    """A video file's frames in order, labelled `PATH#N`."""

    path: str
    size: tuple[int, int]
    fps: float

    def label(self, index: int) -> str:
        return f"{self.path}#{index}"

    def frames(self) -> Iterator[Frame]:
        """Each frame decoded, as RGB, up to the last one OpenCV's reader gives."""
        capture = _open_capture(self.path)
        if capture is None:
            raise ImageError(self.path, "cannot open it as a video any more")
        try:
            index = 0
            while (bgr := _read(capture)) is not None:
                if bgr.shape[1::-1] != self.size:
                    h, w = bgr.shape[:2]
                    raise ImageError(self.label(index), f"frame is {w}x{h}, not the video's "
                                                        f"{self.size[0]}x{self.size[1]}")
                yield Frame(index, self.label(index), np.ascontiguousarray(bgr[..., ::-1]))
                index += 1
        finally:
            capture.release()


FrameSource = ImageSequence | VideoFrames


def open_video(path: str) -> tuple[VideoFrames | None, list[str]]:
    """(the video, []) or (None, [the one problem]): it must open and its first frame decode."""
    p = Path(path)
    if not p.exists():
        return None, [f"{path}: no such file"]
    if not p.is_file():
        return None, [f"{path}: is not a video file"]
    capture = _open_capture(path)
    if capture is None:
        return None, [f"{path}: cannot read it as a video (OpenCV's reader cannot open it: "
                      f"not a video, corrupt or truncated)"]
    try:
        first = _read(capture)
        fps = float(capture.get(cv2.CAP_PROP_FPS))
    finally:
        capture.release()
    if first is None:
        return None, [f"{path}: a video with no frame OpenCV can decode"]
    h, w = first.shape[:2]
    problem = size_problem(path, w, h)
    if problem:
        return None, [problem]
    return VideoFrames(path, (w, h), fps if math.isfinite(fps) and fps > 0 else DEFAULT_FPS), []


def open_sequence(inputs: Sequence[str]) -> tuple[FrameSource | None, list[str]]:
    """(the sequence, []) or (None, every problem, one line each): one video alone, or image
    files and folders (a folder's images in natural order) all readable and of one size."""
    videos = [path for path in inputs if not Path(path).is_dir() and is_video(path)]
    if videos:
        if len(inputs) > 1:
            return None, [f"{videos[0]}: a video is a sequence of its own; give it alone "
                          f"(not with {len(inputs) - 1} other input(s))"]
        return open_video(videos[0])
    paths, problems = expand_folders(inputs, natural=True)
    size: tuple[int, int] | None = None
    first, other_size = "", None
    for path in paths:
        try:
            h, w = read_image(path).shape[:2]
        except ValueError as err:
            problems.append(str(err))
            continue
        problem = size_problem(path, w, h)
        if problem:
            problems.append(problem)
        elif size is None:
            size, first = (w, h), path
        elif (w, h) != size and other_size is None:  # one line for the first one, not each
            other_size = (f"{path}: frame is {w}x{h} but the sequence's first frame {first} is "
                          f"{size[0]}x{size[1]} (a sequence's frames share one size)")
    problems += [other_size] if other_size else []
    if problems or size is None:
        return None, problems
    return ImageSequence(tuple(paths), size), []


class VideoOut:
    """An annotated video written atomically: the frames go to a hidden file beside `path`,
    renamed into place by `close()`; `abort()` (or leaving a `with` block by an exception)
    leaves nothing behind. OSError when OpenCV cannot write it."""

    def __init__(self, path: str | Path, fps: float, size: tuple[int, int]) -> None:
        self.path = Path(path)
        self.size = size
        cannot = OSError(f"OpenCV cannot write a {VIDEO_FOURCC} video at {self.path}")
        try:  # the writer chooses the container by the suffix: the temporary name keeps it
            self._file = PendingFile(self.path, VIDEO_SUFFIX)
        except OSError:
            raise cannot from None  # a folder where the writer could not have written either
        self._writer, _ = call_quietly(cv2.VideoWriter, str(self._file.tmp),
                                       cv2.VideoWriter_fourcc(*VIDEO_FOURCC), float(fps), size)
        if not self._writer.isOpened():
            self.abort()
            raise cannot
        self.frames = 0

    def write(self, bgr: np.ndarray) -> None:
        if bgr.shape[1::-1] != self.size:
            raise ValueError(f"frame of {bgr.shape[1]}x{bgr.shape[0]} for a video of "
                             f"{self.size[0]}x{self.size[1]}")
        self._writer.write(np.ascontiguousarray(bgr))
        self.frames += 1

    def close(self) -> None:
        self._writer.release()
        tmp = self._file.tmp
        if self.frames == 0 or not tmp.is_file() or tmp.stat().st_size == 0:
            self._file.discard()
            raise OSError(f"OpenCV wrote no video at {self.path}")
        self._file.commit()

    def abort(self) -> None:
        self._writer.release()
        self._file.discard()

    def __enter__(self) -> VideoOut:
        return self

    def __exit__(self, kind, value, traceback) -> None:
        if kind is None:
            self.close()
        else:
            self.abort()
