"""Random worlds for the LaneNet dataset: a whole scenario drawn from one seed.

Paper 000 trains on real video; we train on the simulator, so what must transfer to real photos
is varied in the world itself, not only in the image (lanekeep/evaluation/dataset.py renders
these): roads of 1-5 lanes 3.3-3.9 m wide, straights, arcs and clothoids; asphalt of every tone
and light concrete with cracks, patches and tyre marks, and (their own stream) tar lines,
seams, oil stripes and sections of another surface; solid, dashed, double, worn and Botts'-dot
boundaries, some with raised reflectors; guard rails, barriers, poles, trees, buildings,
overpasses; traffic of every size and colour in every lane; day, dawn, dusk and night, sun
anywhere, shadows, wet, fog, rain, snow; cameras 1.2-1.9 m high with 62-120 deg of horizontal
field of view, pitched so the horizon falls anywhere between rows 200 and 450 of 720, or (a
quarter of the worlds) the `dashcam` preset's front camera (1.4 m, horizon near row 300) with a
56-64 deg lens; rolled and yawed a little; JPEG, noise, vignetting and blur.

`random_scenario(seed)` is a pure function of the seed: the same seed builds the same world.
The shares below were chosen for variety, not tuned on any score.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from lanekeep.geometry.markings import MarkingStyle
from lanekeep.geometry.road import SegmentSpec
from lanekeep.scenario.camera import CameraConfig
from lanekeep.scenario.conditions import Conditions, ShadowZone, VehicleSpec
from lanekeep.scenario.road import RoadConfig, StartConfig
from lanekeep.scenario.roadside import Roadside
from lanekeep.scenario.schema import Scenario, ScenarioError
from lanekeep.scenario.traffic import Traffic
from lanekeep.world.camera_mount import DASHCAM_HFOV_DEG

NOMINAL_FRONT_PITCH_DEG = 10.0  # mjcf/car.xml: the front camera looks 10 deg up
NOMINAL_FRONT_HFOV_DEG = 120.0
DASHCAM_SHARE = 0.25  # worlds seen through the dashcam preset (lanekeep/world/camera_mount.py)
DASHCAM_LENS_HFOV_DEG = (56.0, 64.0)  # their lenses, around the preset's 60 deg
ROAD_LENGTH_M = 420.0
MAX_VEHICLES = 24
WHITE = (0.95, 0.95, 0.92)
YELLOW = (0.9, 0.7, 0.15)
CONDITION_TAGS = ("clear", "shade", "dusk", "night", "wet", "fog", "rain", "snow")


def _pick(rng: np.random.Generator, options: dict):
    keys = list(options)
    p = np.asarray(list(options.values()), dtype=float)
    return keys[int(rng.choice(len(keys), p=p / p.sum()))]


def _segments(rng: np.random.Generator) -> tuple[SegmentSpec, ...]:
    """A lead straight, then straights, arcs and clothoids to ROAD_LENGTH_M (radius >= 60 m)."""
    segs = [SegmentSpec("straight", float(rng.uniform(40.0, 80.0)))]
    k = 0.0
    while sum(s.length_m for s in segs) < ROAD_LENGTH_M:
        kind = _pick(rng, {"straight": 0.3, "arc": 0.35, "clothoid": 0.35})
        length = float(rng.uniform(40.0, 120.0))
        target = float(rng.choice([-1.0, 1.0]) * rng.choice(
            [rng.uniform(1 / 1500, 1 / 400), rng.uniform(1 / 400, 1 / 150),
             rng.uniform(1 / 150, 1 / 60)], p=[0.4, 0.4, 0.2]))
        if kind == "straight":
            if abs(k) > 1e-9:  # ease out first
                segs.append(SegmentSpec("clothoid", 40.0, k, 0.0))
            segs.append(SegmentSpec("straight", length))
            k = 0.0
        elif kind == "clothoid":
            segs.append(SegmentSpec("clothoid", length, k, target))
            k = target
        else:
            if abs(k - target) > 1e-9:
                segs.append(SegmentSpec("clothoid", 40.0, k, target))
            segs.append(SegmentSpec("arc", length, target))
            k = target
    return tuple(segs)


def _marking(rng: np.random.Generator, inner: bool, colour) -> MarkingStyle:
    width = float(rng.uniform(0.10, 0.20))
    if not inner:
        kind = _pick(rng, {"solid": 0.8, "worn": 0.1, "none": 0.1})
        return MarkingStyle(kind=kind, width_m=width, colour=colour, pattern="solid",
                            wear=float(rng.uniform(0.2, 0.6)))
    kind = _pick(rng, {"dashed": 0.45, "dots": 0.2, "worn": 0.15, "solid": 0.1, "double": 0.1})
    dash = float(rng.uniform(2.5, 4.5))
    return MarkingStyle(kind=kind, width_m=width, dash_m=dash, gap_m=float(rng.uniform(6.0, 10.0)),
                        colour=colour, wear=float(rng.uniform(0.2, 0.6)),
                        pattern=_pick(rng, {"dashed": 0.6, "solid": 0.3, "double": 0.1}),
                        dot_spacing_m=float(rng.uniform(0.8, 1.3)))


def _markings(rng: np.random.Generator, n_lanes: int) -> tuple[MarkingStyle, ...]:
    """Rightmost first. Now and then the left edge is yellow (a divided highway's median) or
    the middle of a two-lane road is a double yellow line."""
    left_colour = YELLOW if rng.random() < 0.3 else WHITE
    styles = [_marking(rng, False, WHITE)]
    styles += [_marking(rng, True, WHITE) for _ in range(n_lanes - 1)]
    styles.append(_marking(rng, False, left_colour))
    if n_lanes == 2 and rng.random() < 0.3:
        styles[1] = MarkingStyle(kind="double", width_m=0.12, colour=YELLOW)
    return tuple(styles)


def _camera(rng: np.random.Generator, dashcam: bool = False) -> CameraConfig:
    """A camera whose horizon falls between rows 200 and 450 (front, at 720 rows), or with
    `dashcam` the dashcam preset's front camera (1.4 m, horizon near row 300), its lens
    56-64 deg from the same draw. Both make the same draws, so the rest of a world does not
    depend on the choice."""
    hfov = float(rng.uniform(62.0, 120.0))
    nominal = math.tan(math.radians(NOMINAL_FRONT_HFOV_DEG / 2))
    if dashcam:
        low, high = DASHCAM_LENS_HFOV_DEG
        hfov = low + (high - low) * (hfov - 62.0) / (120.0 - 62.0)
        nominal = math.tan(math.radians(DASHCAM_HFOV_DEG / 2))
    fov_scale = math.tan(math.radians(hfov / 2)) / nominal
    f = 640.0 / math.tan(math.radians(hfov / 2))
    horizon = float(rng.uniform(200.0, 450.0))
    # Pitching up (+, the mount's sign) moves the horizon down the image. Until 2026-11-29
    # this sign was reversed: the drawn rows 200-450 rendered at 270-519, mirrored about the
    # centre row (docs/experiments.md, session 13, "What the dataset contains").
    pitch = math.degrees(math.atan((horizon - 359.5) / f))
    camera = CameraConfig(
        width=640, height=360,
        read_noise_dn=float(rng.uniform(0.5, 3.0)),
        vignetting=float(rng.uniform(0.0, 0.4)),
        lens_blur_px=0.4,  # the loop's 0.8 px at 1280 wide, at the dataset's 640
        jpeg_quality=int(rng.integers(30, 96)) if rng.random() < 0.6 else 0,
        show_hood=bool(rng.random() < 0.5),
        mount_height_m=float(rng.uniform(1.2, 1.9)),
        pitch_offset_deg=pitch - NOMINAL_FRONT_PITCH_DEG,
        roll_deg=float(rng.uniform(-2.0, 2.0)),
        yaw_offset_deg=float(rng.uniform(-3.0, 3.0)),
        fov_scale=float(fov_scale),
    )
    if dashcam:  # the preset's height and pitch instead of the drawn ones
        camera = dataclasses.replace(camera, preset="dashcam", mount_height_m=0.0,
                                     pitch_offset_deg=0.0)
    return camera


def near_rear_mount(camera: CameraConfig, rng: np.random.Generator) -> CameraConfig:
    """`camera` with its mount drawn near the car's own (mjcf/car.xml; the rear camera: 150 deg
    wide, 1.5 m high, 20 deg down): height 1.35-1.65 m, pitch and yaw within 3 deg, roll
    within 2 deg, field of view scaled 0.8-1.1 (rear: 143-153 deg). Image settings (noise,
    JPEG, vignetting, hood) stay the world's. The front preset goes back to the car's
    (a rear-only recipe does not render the front)."""
    return dataclasses.replace(
        camera, preset=CameraConfig.preset,
        mount_height_m=float(rng.uniform(1.35, 1.65)),
        pitch_offset_deg=float(rng.uniform(-3.0, 3.0)),
        roll_deg=float(rng.uniform(-2.0, 2.0)),
        yaw_offset_deg=float(rng.uniform(-3.0, 3.0)),
        fov_scale=float(rng.uniform(0.8, 1.1)))


def _traffic(rng: np.random.Generator, n_lanes: int) -> tuple[VehicleSpec, ...]:
    """Vehicles spread along the whole road (the dataset renders many places on it): none, or
    0.5-4 per 100 m of road per lane, at least 9 m apart in a lane."""
    if rng.random() < 0.25:
        return ()
    density = float(rng.uniform(0.5, 4.0))
    vehicles, taken = [], []
    for _ in range(min(MAX_VEHICLES, int(rng.poisson(density * n_lanes * ROAD_LENGTH_M / 100)))):
        lane = int(rng.integers(n_lanes))
        s = float(rng.uniform(15.0, ROAD_LENGTH_M - 15.0))
        if any(lane == ln and abs(s - other) < 9.0 + 8.0 for ln, other in taken):
            continue
        kind = _pick(rng, {"car": 0.65, "van": 0.2, "truck": 0.15})
        length, width, height = {"car": (4.5, 1.85, 1.5), "van": (5.2, 2.0, 2.3),
                                 "truck": (12.0, 2.5, 3.6)}[kind]
        grey = float(rng.uniform(0.05, 0.95))
        colour = (tuple(float(c) for c in rng.uniform(0.05, 0.95, 3)) if rng.random() < 0.6
                  else (grey, grey, grey))
        taken.append((lane, s))
        vehicles.append(VehicleSpec(
            lane=lane, s_m=s, speed_mps=float(rng.uniform(0.0, 3.0)),
            offset_m=float(rng.uniform(-0.3, 0.3)), length_m=length * float(rng.uniform(0.9, 1.1)),
            width_m=width, height_m=height * float(rng.uniform(0.9, 1.1)), colour=colour))
    return tuple(vehicles)


def _conditions(rng: np.random.Generator, tag: str, n_lanes: int, ego_lane: int) -> Conditions:
    time_of_day = {"dusk": str(rng.choice(["dawn", "dusk"])), "night": "night"}.get(tag, "day")
    shadows = ()
    azimuth = float(rng.uniform(-180.0, 180.0))
    if tag == "shade" or rng.random() < 0.15:
        # Casters stand on the sun's side (their shadows must fall onto the road) and the sun
        # is well off the road's axis, so that curves do not turn the shadows away.
        azimuth = float(rng.choice([-1.0, 1.0]) * rng.uniform(35.0, 145.0))
        side = "left" if azimuth > 0 else "right"
        zones = []
        s = float(rng.uniform(20.0, 60.0))
        while s < ROAD_LENGTH_M - 40.0:
            length = float(rng.uniform(30.0, 120.0))
            zones.append(ShadowZone(
                s_start_m=s, s_end_m=min(s + length, ROAD_LENGTH_M - 10.0),
                kind=_pick(rng, {"buildings": 0.5, "trees": 0.5}),
                side=side,
                reach=float(rng.uniform(0.3, 1.4)), coverage=float(rng.uniform(0.2, 1.0)),
                darkness=float(rng.uniform(0.3, 0.75))))
            s += length + float(rng.uniform(10.0, 80.0))
        shadows = tuple(zones)
    return Conditions(
        time_of_day=time_of_day,
        sun_elevation_deg=float(rng.uniform(8.0, 80.0)),
        sun_azimuth_deg=azimuth,
        shadows=shadows,
        wet=float(rng.uniform(0.4, 1.0)) if tag in ("wet", "rain") else 0.0,
        fog=float(rng.uniform(0.2, 0.8)) if tag == "fog" else 0.0,
        rain=float(rng.uniform(0.2, 0.9)) if tag == "rain" else 0.0,
        snow=float(rng.uniform(0.2, 0.8)) if tag == "snow" else 0.0,
        noise=float(rng.uniform(0.0, 0.5)),
        motion_blur=float(rng.uniform(0.0, 0.6)) if rng.random() < 0.5 else 0.0,
        vehicles=_traffic(rng, n_lanes),
    )


def _roadside(rng: np.random.Generator) -> Roadside:
    def sides(p: float) -> tuple[str, ...]:
        return tuple(s for s in ("left", "right") if rng.random() < p)

    rails = sides(0.35)
    barriers = tuple(s for s in sides(0.25) if s not in rails)
    return Roadside(
        guard_rail_sides=rails,
        barrier_sides=barriers,
        pole_spacing_m=float(rng.uniform(30.0, 80.0)) if rng.random() < 0.5 else 0.0,
        pole_sides=sides(0.6) or ("right",),
        signs_m=tuple(float(s) for s in rng.uniform(60.0, 380.0, int(rng.integers(0, 3)))),
        gantries_m=tuple(float(s) for s in rng.uniform(60.0, 380.0, int(rng.random() < 0.2))),
        overpasses_m=tuple(float(s) for s in rng.uniform(80.0, 380.0, int(rng.random() < 0.2))),
        trees_per_100m=float(rng.uniform(0.0, 8.0)) if rng.random() < 0.6 else 0.0,
        buildings_per_100m=float(rng.uniform(0.0, 3.0)) if rng.random() < 0.3 else 0.0,
        skyline=_pick(rng, {"none": 0.3, "hills": 0.45, "city": 0.25}),
        shadow_darkness=float(rng.uniform(0.35, 0.7)),
    )


def _structure(seed: int) -> dict:
    """The road's structure (#59: tar lines, seams, an oil stripe, sections of another surface)
    and raised reflectors on the inner lines, from their own stream so that every other draw
    of the world stays: the false lines a detector must learn to ignore."""
    rng = np.random.default_rng([seed, 0x5EA5])
    return dict(
        tar_lines=float(rng.uniform(0.0, 1.0)) if rng.random() < 0.5 else 0.0,
        seams=float(rng.uniform(0.2, 1.0)) if rng.random() < 0.3 else 0.0,
        oil_stripe=float(rng.uniform(0.2, 0.8)) if rng.random() < 0.4 else 0.0,
        surface_changes=float(rng.uniform(0.1, 0.6)) if rng.random() < 0.25 else 0.0,
        section_surface=_pick(rng, {"repaved": 0.5, "asphalt": 0.25, "concrete": 0.25}),
        reflector_spacing_m=float(rng.uniform(10.0, 24.0)) if rng.random() < 0.3 else 0.0,
    )


def _with_reflectors(markings: tuple[MarkingStyle, ...], spacing_m: float
                     ) -> tuple[MarkingStyle, ...]:
    """The inner lines with raised reflectors every `spacing_m` (0: as they are)."""
    if spacing_m <= 0.0:
        return markings
    inner = [dataclasses.replace(m, reflector_spacing_m=spacing_m) for m in markings[1:-1]]
    return (markings[0], *inner, markings[-1])


def draw_tag(rng: np.random.Generator) -> str:
    return _pick(rng, {"clear": 0.34, "shade": 0.14, "dusk": 0.08, "night": 0.1, "wet": 0.08,
                       "fog": 0.08, "rain": 0.1, "snow": 0.08})


def random_scenario(seed: int, tag: str | None = None, attempts: int = 20) -> Scenario:
    """The world of `seed` (condition `tag`, or one drawn from the seed). A draw the world
    builder rejects (e.g. shadows the sun cannot cast) is redrawn from the same stream."""
    rng = np.random.default_rng([seed, 0xDA7A])
    # Its own stream, so that the other worlds keep the draws they had before the preset.
    dashcam = bool(np.random.default_rng([seed, 0xDA5C]).random() < DASHCAM_SHARE)
    tag = tag or draw_tag(rng)
    if tag not in CONDITION_TAGS:
        raise ValueError(f"condition tag must be one of {CONDITION_TAGS}, got {tag!r}")
    structure = _structure(seed)
    reflectors = structure.pop("reflector_spacing_m")
    last: Exception | None = None
    for _ in range(attempts):  # a road that curves the shadows away is drawn again
        n_lanes = int(rng.choice([1, 2, 3, 4, 5], p=[0.05, 0.3, 0.3, 0.25, 0.1]))
        ego = int(rng.integers(n_lanes))
        concrete = rng.random() < 0.4
        try:
            scenario = Scenario(
                name=f"dataset_{seed}_{tag}",
                description=f"random dataset world, seed {seed}, condition {tag}",
                road=RoadConfig(
                    segments=_segments(rng), n_lanes=n_lanes,
                    lane_width_m=float(rng.uniform(3.3, 3.9)), ego_lane=ego,
                    markings=_with_reflectors(_markings(rng, n_lanes), reflectors),
                    start_heading_deg=float(rng.uniform(-180, 180)),
                    surface="concrete" if concrete else "asphalt",
                    asphalt_tone=float(rng.uniform(0.0, 1.0)),
                    cracks=float(rng.uniform(0.0, 0.8)), patches=float(rng.uniform(0.0, 0.6)),
                    tyre_marks=float(rng.uniform(0.0, 0.8)), **structure),
                seed=int(seed),
                start=StartConfig(s_m=30.0),
                camera=_camera(rng, dashcam),
                conditions=_conditions(rng, tag, n_lanes, ego),
                roadside=_roadside(rng),
                # The sets' vehicles drift at 0-3 m/s over a second of frames: the traffic
                # model of the sets as first rendered (no IDM), so the sets stay the same.
                traffic=Traffic(model="constant"),
            )
            from lanekeep.world.build import check_buildable  # the builder's cross-field checks
            check_buildable(scenario)
            return scenario
        except (ScenarioError, ValueError) as err:
            last = err
    raise RuntimeError(f"no valid world for seed {seed} in {attempts} draws: {last}")
