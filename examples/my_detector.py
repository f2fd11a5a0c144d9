"""Bring your own lane detector: define it here, register it by name, run it as a front model.

The detector below is deliberately simple: the brightest pixels of the road below the horizon
are taken for paint, projected onto the ground through the camera model, split into the left
and right boundary by side, and a parabola is fitted to each. It meets the `Detector` protocol
(detectors/base.py): `name`, `x_ref`, `window`, `detect(frame)`, `reset()`.

    python examples/my_detector.py                          # 20 s of clear_straight
    python examples/my_detector.py --seconds 3 --size 320x180
"""

import argparse
import dataclasses

# lanekeep before numpy: it pins numpy's kernels as they load, so that this run computes what
# the CLI and another machine compute (docs/reproducibility.md).
import lanekeep  # noqa: F401

# isort: split
import numpy as np

from lanekeep.detectors.base import LaneEstimate
from lanekeep.detectors.config import GroundWindow
from lanekeep.detectors.registry import register_detector
from lanekeep.geometry.camera_model import CameraModel
from lanekeep.geometry.lane_poly import LanePoly
from lanekeep.loop.episode import Episode
from lanekeep.scenario.schema import load_scenario


class BrightPaintDetector:
    """Paint = the brightest 4% of the road pixels; one parabola per side of the car."""

    name = "bright_paint"
    x_ref = 4.0  # the offset is reported 4 m ahead (vehicle frame, metres)

    def __init__(self, camera: CameraModel, config=None, distortion=None) -> None:
        self.camera = camera  # the registry passes the camera the detector looks through
        self._window = GroundWindow(x_near_m=4.0, x_far_m=20.0, y_half_m=6.0)

    @property
    def window(self) -> GroundWindow:
        return self._window

    def reset(self) -> None:
        """Nothing is carried between frames."""

    def detect(self, frame: np.ndarray) -> LaneEstimate:
        h, w = frame.shape[:2]
        camera = self.camera if (self.camera.width, self.camera.height) == (w, h) \
            else self.camera.scaled(w, h)
        top = int(max(camera.horizon_row(), 0)) + 2
        grey = frame[top:, :, :].mean(axis=2)
        threshold = max(np.percentile(grey, 96), 100.0)
        rows, cols = np.nonzero(grey >= threshold)
        if len(rows) < 20:
            return LaneEstimate.invalid("too few bright pixels", x_m=self.x_ref)
        ground, ok = camera.pixels_to_ground(np.stack([cols + 0.5, rows + top + 0.5], axis=1))
        x, y = ground[ok, 0], ground[ok, 1]
        near = (x >= self._window.x_near_m) & (x <= self._window.x_far_m) & (np.abs(y) < 3.0)
        x, y = x[near], y[near]
        sides = {}
        for side, mask in (("left", y > 0.0), ("right", y < 0.0)):
            span = np.ptp(x[mask]) if mask.sum() >= 10 else 0.0
            if span < 1.5:  # a dashed line may show one dash only: a straight fit then
                return LaneEstimate.invalid(f"no {side} boundary", x_m=self.x_ref)
            degree = 2 if span >= 8.0 else 1
            coeffs = np.polyfit(x[mask], y[mask], degree)[::-1]  # low order first
            sides[side] = np.pad(coeffs, (0, 3 - len(coeffs)))
        centre = (sides["left"] + sides["right"]) / 2.0
        return LaneEstimate(valid=True, offset_m=float(LanePoly.of(centre).offset_m(self.x_ref)),
                            x_m=self.x_ref, left=sides["left"], right=sides["right"],
                            confidence=1.0)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=None)
    parser.add_argument("--size", default=None, help="camera size WxH (default: the scenario's)")
    args = parser.parse_args()

    register_detector("bright_paint", BrightPaintDetector)
    scenario = load_scenario("clear_straight")
    scenario = dataclasses.replace(
        scenario, estimation=dataclasses.replace(scenario.estimation,
                                                 front_detectors=("hough", "bright_paint")))
    if args.seconds is not None:
        scenario = dataclasses.replace(scenario, duration_s=args.seconds)
    size = tuple(int(v) for v in args.size.split("x")) if args.size else None

    with Episode(scenario, render_size=size) as episode:
        report = episode.run()
    for source in ("hough", "bright_paint", "fused"):
        r = report.sources[source]
        print(f"{source:<14} offset RMSE {r.rmse_cm:6.1f} cm, valid on {r.valid_share:.0%} "
              f"of the frames")
    print(f"lane departures: {report.lane_departures}")


if __name__ == "__main__":
    main()
