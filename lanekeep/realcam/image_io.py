"""Reading real photos strictly: a missing, empty, truncated or corrupt file is an error.

OpenCV decodes what it can: a JPEG cut short (an interrupted copy, a dashcam that lost power) comes
back as a whole-size image whose lower part is grey, with only a libjpeg warning on stderr. So
`read_image` checks the file's structure before decoding it:

- JPEG (starts FF D8): the marker segments are walked by their lengths (so an EXIF thumbnail's
  own end marker is skipped), and each scan's entropy-coded data up to the next marker (FF
  followed by anything but 00, FF or a restart marker D0-D7). The file is complete when this walk
  reaches the end-of-image marker FF D9; if the data runs out first it is truncated. Bytes after
  FF D9 are ignored (zero padding, the video a "motion photo" appends), but zero padding in place
  of missing data (a preallocated file cut short) is still truncation: the walk never meets FF D9.
- PNG (the 8-byte signature): the chunks are walked by their lengths up to IEND; a chunk that
  runs past the end of the data, or no IEND, is truncation; a critical chunk (IHDR, PLTE, IDAT,
  IEND) whose CRC does not match is corruption.
- Anything else OpenCV decodes (BMP, TIFF, WebP, ...) is taken as it decodes.

Then the data is decoded with cv2.imdecode while the process's stderr (fd 2) goes to a temporary
file: libjpeg's warnings that mean lost pixels (premature end of data, bad Huffman code, a lost
restart marker) turn into an error, and none of OpenCV's or libjpeg's chatter reaches the user.
Harmless warnings (extraneous bytes between segments, a bad ICC marker) are dropped.
"""

from __future__ import annotations

import os
import re
import struct
import tempfile
import zlib
from collections.abc import Callable
from pathlib import Path
from typing import TypeVar

import cv2
import numpy as np

from lanekeep.core.config_io import ConfigError

PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"
JPEG_SOI = b"\xff\xd8"
# libjpeg warnings after which part of the picture is not the file's (lost or invented pixels).
_JPEG_DAMAGE = ("Premature end of JPEG file", "premature end of data segment",
                "bad Huffman code", "instead of RST")
# In entropy-coded data a marker is FF (after any FF fill bytes) followed by a byte that is not
# 00 (a stuffed FF data byte) and not a restart marker D0-D7.
_NEXT_MARKER = re.compile(rb"\xff+[^\x00\xd0-\xd7\xff]")
T = TypeVar("T")


class ImageError(ConfigError):
    """An input image that cannot be used; str() is "PATH: what is wrong"."""

    def __init__(self, path: str | Path, message: str):
        super().__init__(str(path), "", message)


def jpeg_problem(data: bytes) -> str | None:
    """Why the JPEG `data` is incomplete, or None when its marker walk reaches end-of-image."""
    n, i = len(data), 2
    while i < n:
        if data[i] != 0xFF:  # junk between segments: libjpeg skips it too
            i = data.find(b"\xff", i)
            if i < 0:
                break
            continue
        while i + 1 < n and data[i + 1] == 0xFF:  # fill bytes
            i += 1
        if i + 1 >= n:
            break
        marker = data[i + 1]
        if marker == 0xD9:
            return None
        if 0xD0 <= marker <= 0xD7 or marker in (0x01, 0xD8):  # no length field
            i += 2
            continue
        if i + 4 > n:
            break
        end = i + 2 + struct.unpack(">H", data[i + 2:i + 4])[0]
        if end > n:
            break
        i = end
        if marker == 0xDA:  # start of scan: entropy-coded data up to the next marker
            found = _NEXT_MARKER.search(data, i)
            if found is None:
                break
            i = found.end() - 2
    return "truncated JPEG: the data ends before the end-of-image marker (incomplete file)"


def png_problem(data: bytes) -> str | None:
    """Why the PNG `data` is incomplete or corrupt, or None when its chunks reach IEND intact."""
    n, i = len(data), len(PNG_SIGNATURE)
    while i + 8 <= n:
        length, kind = struct.unpack(">I4s", data[i:i + 8])
        end = i + 12 + length
        if end > n:
            break
        name = kind.decode("latin-1")
        critical = kind[:1].isupper()
        crc = struct.unpack(">I", data[end - 4:end])[0]
        if critical and zlib.crc32(data[i + 4:end - 4]) != crc:
            return f"corrupt PNG: the {name} chunk's checksum does not match"
        if kind == b"IEND":
            return None
        i = end
    return "truncated PNG: the data ends before the IEND chunk (incomplete file)"


def call_quietly(fn: Callable[..., T], *args: object) -> tuple[T, str]:
    """fn(*args) with the process's stderr (fd 2) captured: (its result, what was printed there).

    Native decoders (libjpeg, FFmpeg) write their warnings to fd 2 directly, past sys.stderr;
    captured, they become the caller's to judge and never reach the user."""
    try:
        saved = os.dup(2)
    except OSError:  # no stderr to redirect
        return fn(*args), ""
    try:
        with tempfile.TemporaryFile() as sink:
            os.dup2(sink.fileno(), 2)
            try:
                result = fn(*args)
            finally:
                os.dup2(saved, 2)
            sink.seek(0)
            said = sink.read().decode("utf-8", "replace")
    finally:
        os.close(saved)
    return result, said


def _decode_quietly(data: bytes) -> tuple[np.ndarray | None, str]:
    """cv2.imdecode with fd 2 captured: (BGR image or None, what the decoders printed)."""
    return call_quietly(cv2.imdecode, np.frombuffer(data, np.uint8), cv2.IMREAD_COLOR)


def read_image(path: str | Path) -> np.ndarray:
    """The photo at `path` as an RGB uint8 array; ImageError naming the file when it is unusable."""
    p = Path(path)
    try:
        data = p.read_bytes()
    except FileNotFoundError:
        raise ImageError(path, "no such file") from None
    except IsADirectoryError:
        raise ImageError(path, "is a folder, not an image file") from None
    except OSError as err:
        raise ImageError(path, f"cannot read it: {err.strerror or err}") from None
    if not data:
        raise ImageError(path, "empty file (0 bytes)")
    kind = None
    if data.startswith(JPEG_SOI):
        kind, problem = "JPEG", jpeg_problem(data)
    elif data.startswith(PNG_SIGNATURE):
        kind, problem = "PNG", png_problem(data)
    else:
        problem = None
    if problem:
        raise ImageError(path, problem)
    image, said = _decode_quietly(data)
    if image is None:
        what = f"corrupt {kind}" if kind else "not an image"
        raise ImageError(path, f"{what} (OpenCV cannot decode it)")
    if kind == "JPEG":
        damage = [line.strip() for line in said.splitlines()
                  if any(key in line for key in _JPEG_DAMAGE)]
        if damage:
            raise ImageError(path, f"corrupt JPEG (libjpeg: {damage[0]})")
    return np.ascontiguousarray(image[..., ::-1])
