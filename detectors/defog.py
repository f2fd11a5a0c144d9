"""Fog taken out of a frame row by row, so that the classical models see paint's contrast.

Fog (and haze) mixes each pixel with the fog's colour by how far its ray runs through it:
I = t J + (1 - t) A, with J the scene, A the airlight (the fog's colour, what the horizon
shows) and t in (0, 1] the transmission. Paint's step over the road shrinks with t, and so
does its ratio to the road, until far paint falls below both models' thresholds, which
were set where t is 1 (`python -m lanekeep.tuning.classical_errors --condition fog`). A flat
road seen by a forward camera has one distance per image row, so t is one number per row, and
the road itself measures it: its level rises from the near rows towards A with distance. From
that rise, t(row) = (A - road(row)) / (A - road near the car), and J = A - (A - I) / t.

The fog is read only from what the camera sees and its calibration (the horizon row, each
row's ground distance): the airlight is the median colour of a band just above the horizon,
the road's level per row the median of the image's middle columns. It is taken for fog only
when the horizon band is of one colour (`MAX_HORIZON_SPREAD`) and brighter than the near road
by `MIN_AIR_STEP` grey levels, and the road 30-45 m ahead has risen between `RISE` of the way
towards it: without fog the far road is as dark as the near one (a clear day), or the horizon
is darker than the road (trees, buildings, night), or a pattern (a skyline in clear air). The
transmission is relative to the road 6-12 m ahead (`NEAR_M`), which is taken for clear: the
cleared frame is the road as it looks there. Transmission never rises with distance (a sunlit
patch ahead of a shaded one is not clearer air), and is never below `MIN_TRANSMISSION`
(beyond that, noise only).

Distances are ahead of the car (vehicle x): a rear camera's rows lie behind it, so its frames
are left as they are (the rear models were not measured with it).
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

from lanekeep.geometry.camera_model import CameraModel

MIN_AIR_STEP = 25.0  # grey levels the horizon band stands above the near road, at least
# Fog makes the horizon one colour (everything that far is airlight); buildings, trees or a
# skyline in clear air make it a pattern. The band's grey spread (SD) is at most this: on the
# tuning eval sets (2026-12-02) 5-30 where the fog set's frames were taken for fog, 22-83
# where a sunlit road ahead of building shade passed the rise test (buildings, half shade).
MAX_HORIZON_SPREAD = 25.0
RISE = (0.3, 1.2)  # the far road's rise towards the airlight, a share of the whole way
NEAR_M = (6.0, 12.0)  # ground distances (m) of the rows that give the road's own level
FAR_M = (30.0, 45.0)  # ... and of the rows whose rise tells fog
MIN_TRANSMISSION = 0.15
HORIZON_BAND = 0.03  # share of the image's rows above the horizon that give the airlight
MIDDLE = (0.3, 0.7)  # the columns (shares of the width) the road's level is read in


@dataclass(frozen=True)
class Fog:
    """A frame's fog: its colour and the transmission of each full-resolution row from
    `first_row` down (1 where there is no fog to take out)."""

    airlight: np.ndarray  # RGB, float32 (3,)
    first_row: int
    transmission: np.ndarray  # float32 (rows,)

    def clear(self, image: np.ndarray, top: int, scale: float) -> np.ndarray:
        """`image` (uint8 RGB or grey: the frame's rows from `top` down, resized by `scale`)
        without the fog: J = A - (A - I) / t on each row."""
        rows = top + (np.arange(image.shape[0]) + 0.5) / scale  # full-resolution rows
        index = np.clip(np.floor(rows).astype(int) - self.first_row, 0,
                        len(self.transmission) - 1)
        t = np.where(rows >= self.first_row, self.transmission[index], 1.0).astype(np.float32)
        air = self.airlight if image.ndim == 3 else np.float32(_grey(self.airlight))
        shape = (-1, 1, 1) if image.ndim == 3 else (-1, 1)
        out = air - (air - image.astype(np.float32)) / t.reshape(shape)
        return np.clip(out, 0.0, 255.0).round().astype(np.uint8)


def estimate_fog(frame: np.ndarray, camera: CameraModel) -> Fog | None:
    """The frame's fog, or None where the frame shows none (see the module docstring)."""
    h, w = frame.shape[:2]
    horizon = camera.horizon_row()
    if not np.isfinite(horizon) or not 0 <= horizon < h - 2:
        return None
    horizon_row = int(horizon)
    band = frame[max(0, horizon_row - int(HORIZON_BAND * h)):horizon_row + 1]
    airlight = np.median(band.reshape(-1, 3), axis=0).astype(np.float32)
    air = _grey(airlight)
    if float(cv2.cvtColor(band, cv2.COLOR_RGB2GRAY).std()) > MAX_HORIZON_SPREAD:
        return None
    first = horizon_row + 2
    rows = np.arange(first, h)
    centre = np.stack([np.full(len(rows), w / 2.0), rows + 0.5], axis=1)
    ground, seen = camera.pixels_to_ground(centre)
    distance = np.where(seen, ground[:, 0], np.inf)  # ahead of the car's origin
    grey = cv2.cvtColor(frame[first:, int(MIDDLE[0] * w):int(MIDDLE[1] * w)],
                        cv2.COLOR_RGB2GRAY)
    road = np.median(grey, axis=1).astype(np.float32)
    near_rows = (distance >= NEAR_M[0]) & (distance <= NEAR_M[1])
    far_rows = (distance >= FAR_M[0]) & (distance <= FAR_M[1])
    if not near_rows.any() or not far_rows.any():
        return None
    near, far = float(np.median(road[near_rows])), float(np.median(road[far_rows]))
    step = air - near
    if step < MIN_AIR_STEP or not RISE[0] * step <= far - near <= RISE[1] * step:
        return None
    t = np.clip((air - road) / step, MIN_TRANSMISSION, 1.0)
    t[distance < NEAR_M[0]] = 1.0
    t = np.minimum.accumulate(t[::-1])[::-1]  # from the car outwards, never clearer
    return Fog(airlight, first, t.astype(np.float32))


def _grey(rgb: np.ndarray) -> float:
    """OpenCV's RGB -> grey weights."""
    return float(0.299 * rgb[0] + 0.587 * rgb[1] + 0.114 * rgb[2])
