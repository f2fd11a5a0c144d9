"""Episode recording. `NullRecorder` costs nothing; `RerunRecorder` writes a rerun .rrd file.

`rerun` is imported only when a `RerunRecorder` is made, so an episode without recording never
loads it. Everything one control step logs is stamped with the time lines `step` (sequence:
the control step index) and `sim_time` (the simulated time at which that step's camera frames
were taken). The episode hands the recorder its static `EpisodeInfo` once and then one
StepResult per step, nothing else; a step carries the pose the frames
were taken from (`StepResult.sensed_pose`); ground truth is drawn from the latter so that it
lines up with the images.

Entity paths (metres; `world` is MuJoCo's frame, z up; lanes of the vehicle frame x forward,
y left are drawn in world coordinates):

    scenario                              static: TOML text, seed, command that reproduces it
    cameras/{front,rear}/image            JPEG (OpenCV, quality configurable)
    cameras/{cam}/segmentation            marking mask (optional layer)
    cameras/{cam}/lanes/{model}/points    pixels each detector fitted (LaneEstimate.image_points)
    cameras/{cam}/lanes/{model}/boundaries  its left/right polynomials projected by the camera
    cameras/{cam}/lanes/{model}/others    the other lanes' lines it reports (LaneEstimate.others)
    cameras/{cam}/lanes/truth             the true ego-lane boundaries projected (green)
    cameras/front/lanes/output/centre     centre of the lane the controller follows (red)
    world/road/boundaries                 static: every lane boundary
    map/road, map/lane                    static: the whole road to scale (2D, x east, y flipped
                                          so that north is up), the ego lane in green
    map/car, map/car/marker, map/path     the car's footprint, a marker, the driven path
    map/vehicles                          the other vehicles' footprints (true, labelled)
    world/car, world/car/body             pose (Transform3D) and a box the car's size
    world/vehicles                        a box for each other vehicle (its footprint, 1.5 m tall)
    world/path                            the driven path so far
    world/lanes/{model}, world/lanes/output  lane estimates in world coordinates
    plots/offset/{truth,model...,reference,fused}  lateral offsets at each look-ahead (cm)
    plots/error/{model...,reference,fused}  estimate - truth at the estimate's look-ahead (cm)
    plots/probability/{model}             MMAE probabilities
    plots/residual/{model}                MMAE residuals (eq. 2): the reference minus the model's
                                          offset carried to where the reference looked (cm)
    plots/car/offset_cm, plots/steer/steer_pct, plots/throttle/throttle_pct,
    plots/speed/speed_mps                 one panel each (one unit a plot); steer and
                                          throttle in % of their range [-1, 1]
    plots/sensors/...                     what the vehicle sensors told the estimator (SI)
    plots/gap/gap_m, plots/ttc/ttc_s      among other vehicles (lanekeep/scoring/safety.py): the
                                          gap to the vehicle ahead in the car's path and the
                                          time to collision with it (while one is ahead; TTC
                                          drawn at most TTC_PLOT_MAX_S, not closing included)
    plots/accel/accel_mps2                the car's true longitudinal acceleration (hard braking
                                          at -0.4 g)
    key                                   static: the colour key (a labelled point per source)
    events                                text: model switches, reference repairs, gated
                                          measurements, lanes lost/found, detector failures,
                                          lane departures, a collision

Scalars and events are logged every step; images, overlays and the 3D view every `every`-th.
Offsets, errors and residuals are plotted in centimetres (the papers' unit; in metres a plot of
errors of a few centimetres showed a lone "0" tick), as reports use them.
"""

from __future__ import annotations

import functools
import math
import queue
import threading
import uuid
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Protocol

import cv2
import numpy as np

from lanekeep.core.busy import CORES_FREE
from lanekeep.core.interrupts import stop_signals_held
from lanekeep.geometry.camera_model import CameraModel
from lanekeep.geometry.road import Road
from lanekeep.report.blueprint import blueprint, key_names, key_positions, scenario_document
from lanekeep.report.overlay import (
    MAX_POINTS_PER_SIDE,
    camera_x_range,
    car_footprint,
    lifted,
    map_xy,
    pixel_strips,
    poly_points,
    vehicle_to_world,
)
from lanekeep.report.palette import (
    CAR_COLOUR,
    COLOURS,
    FUSED,
    OUTPUT,
    PATH_COLOUR,
    REFERENCE,
    ROAD_COLOUR,
    TRUTH,
    VEHICLE_COLOUR,
    colour,
)
from lanekeep.scoring.safety import StepSafety
from lanekeep.scoring.step_result import StepResult
from lanekeep.scoring.truth import LanePolylines

APPLICATION_ID = "lanekeep"
TRUTH_BEHIND_M, TRUTH_AHEAD_M, TRUTH_STEP_M = 25.0, 45.0, 0.5
ROAD_STEP_M = 1.0
BATCH_FLUSH_S, BATCH_BYTES = 2.0, 8 << 20  # rerun's chunk batcher (default 0.2 s, 2 MiB)
CM_PER_M = 100.0  # plots of offsets, errors and residuals are in cm
PERCENT = 100.0  # steer and throttle (each in [-1, 1]) are plotted in %
TTC_PLOT_MAX_S = 10.0  # a TTC above this (or none: not closing) is drawn here: the plot is
# about the last few seconds before a collision, and an infinite TTC has no point to draw
NO_SAFETY = StepSafety()  # a step made without safety truth (a tool's own steps)
VEHICLE_HEIGHT_M = 1.5  # the other vehicles' boxes in the 3D view (their truth has no height)


@dataclass(frozen=True)
class EpisodeInfo:
    """What a recorder is told once, before the first step: nothing it could step with."""

    road: Road
    cameras: dict[str, CameraModel]  # camera name -> its model at the frames' size
    models: list[str]  # the front models, in the MMAE's order
    dt_s: float
    car_size_m: tuple[float, float]  # length, width


class Recorder(Protocol):
    """Receives an episode's static information once, then each control step's result."""

    def start(self, info: EpisodeInfo) -> None: ...

    def wants_masks(self, step_index: int) -> bool:
        """Whether the step with this index should carry the marking masks rendered after it
        (`StepResult.marking_masks_after`)."""
        ...

    def log_step(self, step: StepResult) -> None: ...

    def close(self) -> None: ...


class NullRecorder:
    """Recording off: every call returns at once."""

    def start(self, info: EpisodeInfo) -> None:
        return None

    def wants_masks(self, step_index: int) -> bool:
        return False

    def log_step(self, step: StepResult) -> None:
        return None

    def close(self) -> None:
        return None






class _Truth:
    """What the recording draws and plots as the truth: the step's own offsets (computed once
    by scoring, `StepResult.truth`) and, on steps whose images are logged, the lane's
    polylines to draw (lanekeep.scoring.truth)."""

    def __init__(self, road, lane: int, pose: tuple[float, float, float], step_truth) -> None:
        self._road, self._lane, self._pose, self._truth = road, lane, pose, step_truth

    @functools.cached_property
    def lines(self) -> LanePolylines:
        """Made only on steps whose images are logged."""
        return LanePolylines(self._road, self._lane, self._pose, TRUTH_BEHIND_M,
                             TRUTH_AHEAD_M, TRUTH_STEP_M)

    def offset_m(self, x_m: float) -> float:
        """True offset of the car from the lane centre at look-ahead x (+ = car left)."""
        return self._truth.offset_at(x_m)




















# -- the recorder -------------------------------------------------------------------------------
class RerunRecorder:
    """Streams every step of an episode to a rerun .rrd file, with a default blueprint.

    `start` takes the episode's static information, `log_step` queues each step: a writer
    thread JPEG-encodes, projects and logs, so the loop does not wait for it while the GIL is
    free (physics, OpenCV; it never runs beside a render, see lanekeep.sensing.cameras). The
    queue is
    bounded, so a slow writer slows the loop rather than filling memory. Steps are treated as
    immutable once handed over.

    Args:
        path: the .rrd file (streamed as the episode runs; `close()` writes its footer).
        scenario: the scenario being run; its TOML and seed are stored in the recording.
        every: log images, overlays and the 3D view on every N-th step (scalars: every step).
        jpeg_quality: quality of the camera images (rerun's JPEG encoder), 1..100.
        segmentation: also log the marking mask of both cameras (the episode renders them,
            two extra renders per recorded step, when `wants_masks` says so). They are rendered
            from the state after a step, which is the state the next step's frames come from,
            and logged at that next step: so from step `every` on (none at step 0), and one
            past the last step.
    """

    QUEUE_STEPS = 4

    def __init__(self, path: Path, scenario, every: int = 1, jpeg_quality: int = 75,
                 segmentation: bool = False) -> None:
        if every < 1:
            raise ValueError(f"every must be >= 1, got {every}")
        if not 1 <= jpeg_quality <= 100:
            raise ValueError(f"jpeg_quality must be in 1..100, got {jpeg_quality}")
        import rerun as rr

        self._rr = rr
        self.path = Path(path)
        self.path.parent.mkdir(parents=True, exist_ok=True)
        self.scenario = scenario
        self.every = int(every)
        self.jpeg_quality = int(jpeg_quality)
        self.segmentation = segmentation
        # Chunks of ~2 s per entity instead of one per step: 18 % smaller files, 6x fewer chunks.
        batching = rr.ChunkBatcherConfig(flush_tick=BATCH_FLUSH_S, flush_num_bytes=BATCH_BYTES)
        self._rec = rr.RecordingStream(APPLICATION_ID, recording_id=uuid.uuid4(),
                                       batcher_config=batching)
        self._rec.save(self.path, default_blueprint=blueprint(scenario))
        self._rec.send_recording_name(f"{scenario.name} seed {scenario.seed}")
        self._rec.send_property("scenario", rr.AnyValues(name=scenario.name, seed=scenario.seed,
                                                         source=str(scenario.source)))
        self._rec.log("scenario", rr.TextDocument(scenario_document(scenario),
                                                  media_type=rr.MediaType.MARKDOWN), static=True)
        self._view: EpisodeInfo | None = None
        self._closed = False
        self._error: BaseException | None = None
        # Writer-thread state: the path so far, whether other vehicles were drawn last.
        self._path: list[tuple[float, float]] = []
        self._vehicles_drawn = False
        self._selected: int | None = None
        self._valid: dict[str, bool] = {}
        self._had_others: dict[str, bool] = {}  # entity paths that hold other lanes' lines
        self._queue: queue.Queue = queue.Queue(maxsize=self.QUEUE_STEPS)
        self._writer = threading.Thread(target=self._write_loop, name="rerun-recorder",
                                        daemon=True)
        self._writer.start()

    # -- the episode's thread ------------------------------------------------------------------
    def start(self, info: EpisodeInfo) -> None:
        """The episode's static information; logged once, before the first step."""
        if self._view is not None:
            raise RuntimeError("a RerunRecorder records one episode; start() came twice")
        self._view = info
        self._queue.put(("static", info, None))

    def wants_masks(self, step_index: int) -> bool:
        return self.segmentation and (step_index + 1) % self.every == 0

    def log_step(self, step: StepResult) -> None:
        if self._closed:
            return
        if self._view is None:
            raise RuntimeError("RerunRecorder.start(info) must come before the first step")
        self._raise_writer_error()
        masks = getattr(step, "marking_masks_after", None)
        self._queue.put(("step", step, masks))

    def close(self) -> None:
        """Drain the writer, flush and finalise the file (footer included); safe to repeat."""
        if self._closed:
            return
        self._closed = True
        with stop_signals_held():  # a second Ctrl-C or a SIGTERM would cut its footer
            self._queue.put(None)
            self._writer.join()
            self._rec.flush()
            self._rec.disconnect()
        self._raise_writer_error()

    def __enter__(self) -> RerunRecorder:
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def _raise_writer_error(self) -> None:
        if self._error is not None:
            error, self._error = self._error, None
            raise RuntimeError(f"recording to {self.path} failed: {error!r}") from error

    # -- the writer thread ---------------------------------------------------------------------
    def _write_loop(self) -> None:
        while (item := self._queue.get()) is not None:
            if self._error is not None:
                continue  # keep draining so that the episode never blocks on a full queue
            kind, payload, masks = item
            CORES_FREE.wait()  # lanekeep/core/busy.py: never beside a render or detections
            try:
                if kind == "static":
                    self._log_static(payload)
                else:
                    self._log_step(payload, masks)
            except Exception as err:  # noqa: BLE001 - handed to the episode's thread
                self._error = err

    def _log_step(self, step, masks) -> None:
        rr, rec, view = self._rr, self._rec, self._view
        pose = tuple(step.sensed_pose)  # the pose the frames were taken from
        self._path.append(pose[:2])
        rec.set_time("step", sequence=int(step.index))
        rec.set_time("sim_time", duration=max(0.0, float(step.time_s) - view.dt_s))
        truth = _Truth(view.road, self.scenario.road.ego_lane, pose, step.truth)
        self._log_scalars(step, truth)
        self._log_events(step)
        if step.index % self.every == 0:
            self._log_cameras(step, truth)
            self._log_world(step, pose)
        if masks:
            rec.set_time("step", sequence=int(step.index) + 1)
            rec.set_time("sim_time", duration=float(step.time_s))
            for name, mask in masks.items():
                rec.log(f"cameras/{name}/segmentation", rr.SegmentationImage(mask, opacity=0.5))

    def _sources(self) -> dict[str, str]:
        """Estimate name -> the camera its frame came from."""
        cams = {name: "front" for name in self._view.models}
        cams[REFERENCE] = self.scenario.estimation.reference_camera
        return cams

    def _colour(self, name: str) -> tuple[int, int, int]:
        models = self._view.models
        return colour(name, models.index(name) if name in models else 0)

    def _log_static(self, view: EpisodeInfo) -> None:
        rr, rec, road = self._rr, self._rec, view.road
        s = np.append(np.arange(0.0, road.length_m, ROAD_STEP_M), road.length_m)
        strips = [lifted(road.position(s, road.boundary_r(i))) for i in range(road.n_lanes + 1)]
        rec.log("world", rr.ViewCoordinates.RIGHT_HAND_Z_UP, static=True)
        rec.log("world/road/boundaries",
                rr.LineStrips3D(strips, colors=[ROAD_COLOUR], radii=0.08), static=True)
        length, width = view.car_size_m
        rec.log("world/car/body", rr.Boxes3D(centers=[[0.0, 0.0, 0.75]],
                                             half_sizes=[[length / 2, width / 2, 0.75]],
                                             colors=[CAR_COLOUR]), static=True)
        lane = self.scenario.road.ego_lane
        rec.log("map/road", rr.LineStrips2D([map_xy(b[:, :2]) for b in strips],
                                            colors=[ROAD_COLOUR], radii=0.4), static=True)
        rec.log("map/lane", rr.LineStrips2D([map_xy(strips[lane][:, :2]),
                                             map_xy(strips[lane + 1][:, :2])],
                                            colors=[COLOURS[TRUTH]], radii=0.3), static=True)
        rec.log("cameras", rr.AnnotationContext([(0, "road", (0, 0, 0, 0)),
                                                 (1, "marking", (255, 0, 255, 160))]),
                static=True)
        series = {f"plots/offset/{TRUTH}": TRUTH, f"plots/offset/{REFERENCE}": REFERENCE,
                  f"plots/offset/{FUSED}": FUSED, f"plots/error/{REFERENCE}": REFERENCE,
                  f"plots/error/{FUSED}": FUSED}
        for name in view.models:
            for group in ("offset", "error", "probability", "residual"):
                series[f"plots/{group}/{name}"] = name
            for group in ("offset", "error"):  # the model's own Kalman track
                series[f"plots/{group}/{name}:track"] = name
        for path, name in series.items():
            label = path.rsplit("/", 1)[-1]  # "hough:track" keeps its suffix in the legend
            width = 3.0 if name == FUSED else 1.5
            rec.log(path, rr.SeriesLines(colors=[self._colour(name)], names=[label],
                                         widths=[width]), static=True)
        car_series = {"plots/car/offset_cm": ("offset (cm)", (0, 140, 230)),
                      "plots/steer/steer_pct": ("steer (%)", (220, 20, 20)),
                      "plots/throttle/throttle_pct": ("throttle (%)", (30, 170, 30)),
                      "plots/speed/speed_mps": ("speed (m/s)", (190, 50, 190)),
                      "plots/gap/gap_m": ("gap to the vehicle ahead (m)", VEHICLE_COLOUR),
                      "plots/ttc/ttc_s": ("time to collision (s)", (220, 20, 20)),
                      "plots/accel/accel_mps2": ("acceleration (m/s^2)", (0, 140, 150))}
        for path, (label, rgb) in car_series.items():
            rec.log(path, rr.SeriesLines(colors=[rgb], names=[label], widths=[1.5]), static=True)
        names = key_names(view.models)
        rec.log("key", rr.Points2D(key_positions(len(names)), radii=rr.Radius.ui_points(6.0),
                                   colors=[self._colour(n) for n in names], labels=names,
                                   show_labels=True), static=True)

    def _log_scalars(self, step, truth: _Truth) -> None:
        rr, rec = self._rr, self._rec
        est = self.scenario.estimation

        def cm(path: str, metres: float) -> None:
            rec.log(path, rr.Scalars(CM_PER_M * float(metres)))

        cm(f"plots/offset/{TRUTH}", truth.offset_m(est.offset_lookahead_m))
        for name, estimate in step.estimates.items():
            value = step.reference_m if name == REFERENCE else estimate.offset_m
            if not estimate.valid or value is None:
                continue
            x_m = step.reference_x_m if name == REFERENCE else estimate.x_m
            cm(f"plots/offset/{name}", value)
            cm(f"plots/error/{name}", value - truth.offset_m(x_m))
        x_out = step.output_x_m
        for name, value in step.track_offsets_m.items():
            if value is not None:
                cm(f"plots/offset/{name}:track", value)
                cm(f"plots/error/{name}:track", value - truth.offset_m(x_out))
        if step.output_offset_m is not None:
            cm(f"plots/offset/{FUSED}", step.output_offset_m)
            cm(f"plots/error/{FUSED}", step.output_offset_m - truth.offset_m(x_out))
        for name, p in zip(self._view.models, np.asarray(step.probabilities), strict=False):
            rec.log(f"plots/probability/{name}", rr.Scalars(float(p)))
        for name, r in zip(self._view.models, step.mmae_residuals_m, strict=False):
            if np.isfinite(r):  # NaN: that model was not compared
                cm(f"plots/residual/{name}", r)
        cm("plots/car/offset_cm", truth.offset_m(0.0))
        rec.log("plots/speed/speed_mps", rr.Scalars(float(step.speed_mps)))
        rec.log("plots/steer/steer_pct", rr.Scalars(PERCENT * float(step.steer)))
        signals = step.signals  # what the car's sensors told the estimator
        rec.log("plots/sensors/speed_mps", rr.Scalars(float(signals.speed_mps)))
        rec.log("plots/sensors/yaw_rate_rps", rr.Scalars(float(signals.yaw_rate_rps)))
        rec.log("plots/sensors/accel_lat_mps2", rr.Scalars(float(signals.accel_lat_mps2)))
        rec.log("plots/throttle/throttle_pct", rr.Scalars(PERCENT * float(step.throttle)))
        self._log_safety(getattr(step, "safety", None) or NO_SAFETY)

    def _log_safety(self, safety) -> None:
        """The gap and TTC to the vehicle ahead (while there is one), the car's acceleration."""
        rr, rec = self._rr, self._rec
        rec.log("plots/accel/accel_mps2", rr.Scalars(float(safety.accel_mps2)))
        if safety.gap_m is not None:
            rec.log("plots/gap/gap_m", rr.Scalars(float(safety.gap_m)))
            ttc = safety.ttc_s if math.isfinite(safety.ttc_s) else TTC_PLOT_MAX_S
            rec.log("plots/ttc/ttc_s", rr.Scalars(min(float(ttc), TTC_PLOT_MAX_S)))

    def _log_events(self, step) -> None:
        names = self._view.models
        lines: list[tuple[str, str]] = []
        if self._selected is not None and step.selected != self._selected:
            p = float(np.asarray(step.probabilities)[step.selected])
            lines.append(("INFO", f"model switch: {names[self._selected]} -> "
                                  f"{names[step.selected]} (p = {p:.2f})"))
        self._selected = int(step.selected)
        for name, status in getattr(step, "tracker_status", {}).items():
            if status == "gated":
                lines.append(("WARN", f"tracker {name}: measurement gated"))
        for name, estimate in step.estimates.items():
            was = self._valid.get(name)
            if was is not None and was != estimate.valid:
                text = "lane found" if estimate.valid else f"lane lost ({estimate.reason})"
                lines.append(("INFO", f"detector {name}: {text}"))
            self._valid[name] = estimate.valid
        for text in step.events:
            level = ("WARN" if "departure" in text else
                     "ERROR" if "failed" in text or "returned" in text
                     or text.startswith("collision") else "INFO")
            lines.append((level, text))
        for level, text in lines:
            self._rec.log("events", self._rr.TextLog(text, level=level))

    def _lanes(self, step) -> Iterator[tuple[str, str, list[np.ndarray] | None]]:
        """(source, camera, vehicle-frame polylines or None when it has none) per estimate,
        then the lane the controller follows (its centre)."""
        cameras = self._view.cameras
        for name, cam_name in self._sources().items():
            e = step.estimates.get(name)
            x_range = camera_x_range(cameras[cam_name])
            yield name, cam_name, (None if e is None or not e.valid else
                                   [poly_points(c, x_range) for c in (e.left, e.right)
                                    if c is not None])
        centre = step.output_centre
        x_range = camera_x_range(cameras["front"])
        yield OUTPUT, "front", None if centre is None else [poly_points(centre, x_range)]

    def _log_others(self, base: str, camera, estimate, rgb) -> None:
        """The other lanes' lines a detector reports beside the ego pair, thinner than the
        pair (cleared on a step without them, so a stale line never stays drawn)."""
        x_range = camera_x_range(camera)
        strips = [s for c in estimate.others
                  for s in pixel_strips(camera, poly_points(c, x_range))]
        if strips:
            self._rec.log(f"{base}/others",
                          self._rr.LineStrips2D(strips, colors=[rgb], radii=1.0))
        elif self._had_others.pop(base, False):
            self._rec.log(f"{base}/others", self._rr.Clear(recursive=False))
        if strips:
            self._had_others[base] = True

    def _log_cameras(self, step, truth: _Truth) -> None:
        rr, rec, cameras = self._rr, self._rec, self._view.cameras
        for cam_name, frame in step.frames.items():
            CORES_FREE.wait()
            rec.log(f"cameras/{cam_name}/image", self._jpeg(frame))
            x_range = camera_x_range(cameras[cam_name])
            strips = [strip for b in truth.lines.boundaries(*x_range)
                      for strip in pixel_strips(cameras[cam_name], b)]
            rec.log(f"cameras/{cam_name}/lanes/{TRUTH}",
                    rr.LineStrips2D(strips, colors=[colour(TRUTH)], radii=1.5))
        for name, cam_name, lines in self._lanes(step):
            base = f"cameras/{cam_name}/lanes/{name}"
            if lines is None:
                rec.log(base, rr.Clear(recursive=True))
                continue
            camera, rgb = cameras[cam_name], self._colour(name)
            rec.log(f"{base}/{'centre' if name == OUTPUT else 'boundaries'}",
                    rr.LineStrips2D([s for line in lines for s in pixel_strips(camera, line)],
                                    colors=[rgb],
                                    radii=1.5 if name == OUTPUT else 2.0))
            estimate = step.estimates.get(name)
            if estimate is not None:
                self._log_others(base, camera, estimate, rgb)
            points = [np.asarray(p, dtype=float).reshape(-1, 2)
                      for p in (estimate.image_points.values() if estimate else ())]
            points = [p[:: max(1, len(p) // MAX_POINTS_PER_SIDE)] for p in points]
            points = [p[(p[:, 0] >= 0) & (p[:, 0] <= camera.width) & (p[:, 1] >= 0)
                        & (p[:, 1] <= camera.height)] for p in points]
            if points:
                rec.log(f"{base}/points", rr.Points2D(np.concatenate(points), colors=[rgb],
                                                      radii=2.0))

    def _jpeg(self, frame: np.ndarray):
        """The frame as a JPEG blob. OpenCV's libjpeg-turbo encodes a 1280x720 frame in about
        3 ms, rerun's `Image.compress` (Pillow, which also decodes its result) in about 5: on
        two cores the writer thread takes that time from the loop."""
        ok, data = cv2.imencode(".jpg", cv2.cvtColor(frame, cv2.COLOR_RGB2BGR),
                                [cv2.IMWRITE_JPEG_QUALITY, self.jpeg_quality])
        if not ok:
            raise RuntimeError("JPEG encoding of a camera frame failed")
        return self._rr.EncodedImage(contents=data.tobytes(), media_type="image/jpeg")

    def _log_world(self, step, pose) -> None:
        rr, rec = self._rr, self._rec
        x, y, yaw = pose
        rec.log("world/car", rr.Transform3D(translation=[x, y, 0.0],
                                            rotation=rr.RotationAxisAngle(axis=[0, 0, 1],
                                                                          radians=yaw)))
        path = np.asarray(self._path, dtype=np.float32)
        rec.log("world/path", rr.LineStrips3D([lifted(path)], colors=[PATH_COLOUR],
                                              radii=0.12))
        length, width = self._view.car_size_m
        rec.log("map/path", rr.LineStrips2D([map_xy(path)], colors=[PATH_COLOUR],
                                            radii=rr.Radius.ui_points(1.5)))
        rec.log("map/car", rr.LineStrips2D([map_xy(car_footprint(pose, length, width))],
                                           colors=[CAR_COLOUR], radii=0.25))
        rec.log("map/car/marker", rr.Points2D(map_xy(np.array([[x, y]])), colors=[CAR_COLOUR],
                                              radii=rr.Radius.ui_points(5.0)))
        self._log_vehicles((getattr(step, "safety", None) or NO_SAFETY).vehicles)
        for name, _, lines in self._lanes(step):
            if lines is None:
                rec.log(f"world/lanes/{name}", rr.Clear(recursive=False))
                continue
            strips = [lifted(vehicle_to_world(line, pose)) for line in lines]
            rec.log(f"world/lanes/{name}", rr.LineStrips3D(strips, colors=[self._colour(name)],
                                                           radii=0.08))

    def _log_vehicles(self, footprints) -> None:
        """The other vehicles' true footprints on the map and as boxes in the 3D view; cleared
        once none is left (a recording without traffic logs nothing)."""
        rr, rec = self._rr, self._rec
        if not footprints:
            if self._vehicles_drawn:
                rec.log("map/vehicles", rr.Clear(recursive=False))
                rec.log("world/vehicles", rr.Clear(recursive=False))
                self._vehicles_drawn = False
            return
        names = [f.name for f in footprints]
        rec.log("map/vehicles", rr.LineStrips2D([map_xy(f.outline()) for f in footprints],
                                                colors=[VEHICLE_COLOUR], radii=0.25,
                                                labels=names))
        rec.log("world/vehicles", rr.Boxes3D(
            centers=[[f.x_m, f.y_m, VEHICLE_HEIGHT_M / 2] for f in footprints],
            half_sizes=[[f.length_m / 2, f.width_m / 2, VEHICLE_HEIGHT_M / 2]
                        for f in footprints],
            rotation_axis_angles=[rr.RotationAxisAngle(axis=[0, 0, 1], radians=f.yaw_rad)
                                  for f in footprints],
            colors=[VEHICLE_COLOUR], labels=names))
        self._vehicles_drawn = True
