"""The scenario-format reference (docs/scenario_format.md), generated from the dataclasses.

Types, defaults and the table layout come from lanekeep/scenario/schema.py's dataclasses (and what
they nest), so they cannot drift; what a key means, its allowed values and its sign convention
live in DESCRIPTIONS below, the one place to write them. tests/scenario/test_scenario_reference.py
fails
on a field without a description (naming its dotted key) and on a committed file that differs
from the generated one.

    python -m lanekeep.scenario.reference -o docs/scenario_format.md
"""

from __future__ import annotations

import argparse
import dataclasses
import types
import typing
from collections.abc import Iterator
from pathlib import Path

from lanekeep.estimators.settings import (
    MMAE_INPUTS,
    MMAE_PRIORS,
    MODEL_LANES,
    OUTPUT_AT,
    OUTPUT_MODES,
    RESIDUAL_MODES,
)
from lanekeep.geometry.markings import MARKING_KINDS, WORN_PATTERNS
from lanekeep.geometry.road import MAX_LANES, MAX_ROAD_M, SEGMENT_KINDS
from lanekeep.scenario.roadside import SKYLINES
from lanekeep.scenario.schema import (
    CAMERA_PRESETS,
    CAMERAS,
    ESTIMATION_MODES,
    SHADOW_KINDS,
    SIDES,
    TIMES_OF_DAY,
    Scenario,
)
from lanekeep.scenario.sensors import MAX_SPEED_SCALE_SIGMA, STEERING_RATIO_RANGE
from lanekeep.scenario.traffic import DIRECTIONS, MAX_VEHICLES_PER_KM


def _one_of(values) -> str:
    return ", ".join(f'"{v}"' for v in values)


_UNIT = "0..1"
_SIDES = f"each of {_one_of(SIDES)}, once"
# dotted key -> (what it means, with its sign convention; allowed values). "[]" marks an array
# of tables (`[[road.segments]]`).
DESCRIPTIONS: dict[str, tuple[str, str]] = {
    "name": ("Scenario name, shown in reports.", "any"),
    "description": ("One line saying what the scenario tests.", "any"),
    "seed": ("Seed of every random draw: worn paint, props, image effects, sensor noise.",
             "any integer"),
    "duration_s": ("Simulated length of the episode.", "> 0"),
    "control_period_s": ("Period of the loop: one frame per camera, one control update.", "> 0"),
    "target_speed_mps": ("Speed the speed controller holds.", ">= 0"),
    "road": ("The road: its centre line, lanes, paint and pavement.", ""),
    "road.segments": ("The centre line, piece by piece from the start.", "at least one"),
    "road.segments[].kind": ("Shape of the piece: clothoid = curvature linear in s.",
                             _one_of(SEGMENT_KINDS)),
    "road.segments[].length_m": ("Arc length of the piece.",
                                 f"(0, {MAX_ROAD_M:g}]; all pieces at most {MAX_ROAD_M:g}"),
    "road.segments[].curvature_1pm": (
        "arc: its curvature; clothoid: at its start. + = turning left, - = turning right "
        "(radius = 1 / |curvature|).", "0 for straight"),
    "road.segments[].end_curvature_1pm": ("clothoid: curvature at its end; + = left.",
                                          "0 (or equal to curvature_1pm) unless clothoid"),
    "road.n_lanes": ("Lanes of the carriageway.",
                     f"1..{MAX_LANES}"),
    "road.lane_width_m": ("Width of every lane.", "> 0"),
    "road.ego_lane": ("Lane the car starts in and is scored against; 0 = the rightmost.",
                      "0..n_lanes - 1"),
    "road.markings": ("One paint style per lane boundary, rightmost (boundary 0) first; "
                      "none given = solid edges and dashed lines between lanes.",
                      "none or n_lanes + 1"),
    "road.markings[].kind": ("Paint pattern of the boundary; dots = Botts' dots.",
                             _one_of(MARKING_KINDS)),
    "road.markings[].width_m": ("Width of the line.", "> 0"),
    "road.markings[].dash_m": ("dashed: paint length; dots: length of a row of dots.", "> 0"),
    "road.markings[].gap_m": ("dashed: gap between dashes; dots: gap between rows.", "> 0"),
    "road.markings[].double_gap_m": ("double: clear gap between the two lines.", ">= 0"),
    "road.markings[].wear": ("worn: share of the line without paint, and how faded the rest.",
                             _UNIT),
    "road.markings[].pattern": ("worn: the pattern that wore.", _one_of(WORN_PATTERNS[:3])),
    "road.markings[].dot_diameter_m": ("dots: diameter of one dot.", "> 0"),
    "road.markings[].dot_spacing_m": ("dots: spacing of the dots within a row.", "> 0"),
    "road.markings[].colour": ("Paint colour, RGB (yellow paint: [0.9, 0.7, 0.15]).",
                               "3 values in 0..1"),
    "road.start_heading_deg": ("World heading of the road at its start; + = anticlockwise "
                               "seen from above.", "any"),
    "road.surface": ("Pavement material.", '"asphalt", "concrete"'),
    "road.asphalt_tone": ("0 fresh black .. 1 old, sun-bleached grey.", _UNIT),
    "road.cracks": ("Amount of cracks in the pavement.", _UNIT),
    "road.patches": ("Amount of repair patches.", _UNIT),
    "road.tyre_marks": ("Darker wheel paths and oil strip in every lane.", _UNIT),
    "start": ("Where and how fast the car starts.", ""),
    "start.s_m": ("Where the car starts: arc length along the road.", "any"),
    "start.offset_m": ("Lateral offset from the ego lane's centre; + = left.", "any"),
    "start.heading_deg": ("Heading relative to the road's; + = pointing left.", "any"),
    "start.speed_mps": ("Initial speed.", ">= 0"),
    "start.jitter": ("What a seed other than the file's own draws (uniform within +-each "
                     "half-width; the file's seed is the nominal drive): "
                     "lanekeep/scenario/nuisance.py.", ""),
    "start.jitter.offset_m": ("Half-width of the start's lateral offset draw.", ">= 0"),
    "start.jitter.heading_deg": ("Half-width of the start's heading draw.", ">= 0"),
    "start.jitter.speed_mps": ("Half-width of the speed draw; the start and target speeds "
                               "move together.", ">= 0"),
    "start.jitter.traffic_s": ("Half-width of each vehicle's timing draw: when the car meets "
                               "it (its speed relative to the car's times the draw).", ">= 0"),
    "camera": ("Both onboard cameras: image size, the camera model, the mounting.", ""),
    "camera.width": ("Image width of both onboard cameras.", "> 0"),
    "camera.height": ("Image height of both onboard cameras.", "> 0"),
    "camera.shadows": ("MuJoCo's shadow maps for the lights (costly on a CPU).",
                       "true, false"),
    "camera.antialias_samples": ("MuJoCo's offscreen multisampling.", "0, 2, 4, 8"),
    "camera.read_noise_dn": ("Sensor read noise before the gain.", "0..20"),
    "camera.auto_exposure": ("Causal gain from the past frames' metering.", "true, false"),
    "camera.exposure_time_constant_s": ("How fast the exposure follows the scene.",
                                        "0.01..10"),
    "camera.vignetting": ("Corner darkening of the lens.", "0..0.6"),
    "camera.lens_blur_px": ("Lens + demosaic point spread (Gaussian sigma, pixels); "
                            "0 = off.", "0..3"),
    "camera.bloom": ("Glare around near-saturated areas (sky, lamps); 0 = off.", "0..1"),
    "camera.jpeg_quality": ("JPEG compression of every frame; 0 = off.", "0 or 10..100"),
    "camera.show_hood": ("The car's hood at the bottom of the front image.", "true, false"),
    "camera.mount_height_m": ("Both cameras' height above the ground; 0 = the preset's "
                              "(1.5 m; the dashcam front's 1.4 m).",
                              "0 or 0.5..4"),
    "camera.pitch_offset_deg": ("Added to each camera's pitch; + = looking up.", "-30..30"),
    "camera.roll_deg": ("About each camera's optical axis; + = image turns anticlockwise.",
                        "-20..20"),
    "camera.yaw_offset_deg": ("About the car's vertical axis; + = towards the car's left.",
                              "-30..30"),
    "camera.fov_scale": ("Scales tan(field of view / 2); < 1 = a longer lens (the car's: "
                         "120 deg horizontal).", "0.3..1.5"),
    "camera.preset": ("The front camera's pose before the mounting keys: \"paper\" = the "
                      "car's (1.5 m, 10 deg up, 120 deg horizontal, horizon at row 425 of 720); "
                      "\"dashcam\" = a real dashcam's (1.4 m, 3.1 deg down, 60 deg horizontal, "
                      "horizon at row 300 of 720). The rear camera keeps the car's pose.",
                      _one_of(CAMERA_PRESETS)),
    "camera.distortion": ("OpenCV lens distortion k1, k2, p1, p2, k3 of the front camera; "
                          "every image is bent by it and the detectors are given it. All zero "
                          "= a pinhole; k1 < 0 = barrel (wide lenses). The delivered focal "
                          "length grows by the least factor that keeps the image inside the "
                          "render; coefficients that fold the image are an error.",
                          "5 numbers, each -2..2"),
    "camera.rear_distortion": ("The same for the rear camera (150 deg wide: the polynomial "
                               "model folds early there).", "5 numbers, each -2..2"),
    "conditions": ("Light, weather, surface, traffic and image conditions; all off by "
                   "default.", ""),
    "conditions.time_of_day": ("Light; headlights are on unless day.", _one_of(TIMES_OF_DAY)),
    "conditions.sun_elevation_deg": ("Sun above the horizon.", "2..90"),
    "conditions.sun_azimuth_deg": ("Direction towards the sun from the road's start heading; "
                                   "+ = to the left (anticlockwise).", "any"),
    "conditions.shadows": ("Zones of hard shadows cast across the road.", "any number"),
    "conditions.shadows[].s_start_m": ("Start of the zone along the road.", ">= 0"),
    "conditions.shadows[].s_end_m": ("End of the zone along the road.", "> s_start_m"),
    "conditions.shadows[].kind": ("What casts the shadows.", _one_of(SHADOW_KINDS)),
    "conditions.shadows[].side": ("Side of the road the casters stand on.", _one_of(SIDES)),
    "conditions.shadows[].reach": ("How far across the carriageway the shadows reach; "
                                   "1 = to the far edge line.", "(0, 1.5]"),
    "conditions.shadows[].coverage": ("Share of the zone's length in shadow.", "0.05..1"),
    "conditions.shadows[].darkness": (
        "How dark the shade is, as the casters' optical depth: 0 none, 0.55 a solid "
        "building's shade lit by the open sky (about 0.2-0.35 of the sunlit road's light, "
        "from the sun's height, the time of day and fog; lanekeep/world/shade.py), more "
        "darker still.", _UNIT),
    "conditions.speed_bumps_m": ("Arc length of each speed bump across the road.",
                                 "each >= 0"),
    "conditions.speed_bump_height_m": ("Height of every speed bump.", "0.02..0.15"),
    "conditions.wet": ("0 dry .. 1 soaked: darker, glossier asphalt and puddles.", _UNIT),
    "conditions.fog": ("0 none .. 1 dense (visibility 400 m .. 25 m).", _UNIT),
    "conditions.rain": ("Rain streaks and lens drops (image effect).", _UNIT),
    "conditions.snow": ("Flakes and whitening (image), snow on the verges (world).", _UNIT),
    "conditions.noise": ("Extra sensor noise of the camera model (read + shot noise).", _UNIT),
    "conditions.motion_blur": ("Scale of the speed-proportional motion blur.", _UNIT),
    "conditions.vehicles": ("Other vehicles driving along a lane at constant speed.",
                            "any number"),
    "conditions.vehicles[].lane": ("Its lane; 0 = the rightmost.", "0..n_lanes - 1"),
    "conditions.vehicles[].s_m": ("Arc length of its centre at t = 0.", "any"),
    "conditions.vehicles[].speed_mps": ("Constant speed along s; negative = oncoming (facing "
                                        "the other way).", "any"),
    "conditions.vehicles[].offset_m": ("From its lane's centre; + = left.", "any"),
    "conditions.vehicles[].length_m": ("Body length.", "0.5..20"),
    "conditions.vehicles[].width_m": ("Body width.", "0.5..20"),
    "conditions.vehicles[].height_m": ("Body height.", "0.5..20"),
    "conditions.vehicles[].colour": ("Body colour, RGB.", "3 values in 0..1"),
    "estimation": ("Which detectors run, the MMAE's reference, how the output is formed.", ""),
    "estimation.mode": ("default = our loop; paper = the paper's own loop (overrides "
                        "residual_mode, model_lane and the front windows).",
                        _one_of(ESTIMATION_MODES)),
    "estimation.front_detectors": ("The MMAE's models, front camera, in order. Not set: the "
                                   "mode's own, hough, sliding_window and lanenet (default) or "
                                   "the paper's hough and sliding_window (paper).",
                                   "registered names, package.module:Class, entry points"),
    "estimation.reference_detector": ("The MMAE's reference (the paper's observer).",
                                      "as front_detectors"),
    "estimation.reference_camera": ("Camera the reference detector looks through.",
                                     _one_of(CAMERAS)),
    "estimation.roll_gradient_deg_per_mps2": (
        "The car's body roll per m/s^2 of lateral acceleration, with which each camera's lane "
        "is corrected for roll from the lateral accelerometer (default mode; 0 = off).", ""),
    "estimation.roll_lever_front_m": ("Front camera's offset error per radian of body roll.",
                                      ""),
    "estimation.roll_lever_rear_m": ("Rear camera's offset error per radian of body roll.", ""),
    "estimation.residual_mode": ("distance_aligned: reference and models compared at the same "
                                 "road position; one_step_delay: the paper's eq. 2.",
                                 _one_of(RESIDUAL_MODES)),
    "estimation.output": ("select = the most probable model's lane (the paper); fused = the "
                          "probability-weighted lane; precision = the lanes fused with their "
                          "tracks' covariances, each weighted by its probability.",
                          _one_of(OUTPUT_MODES)),
    "estimation.model_lane": ("What a model hands the output: its Kalman track, or its own "
                              "detection when its track's gate accepts it.",
                              _one_of(MODEL_LANES)),
    "estimation.offset_lookahead_m": ("Where the front offsets are compared and reported.",
                                      "0..40"),
    "estimation.control_lookahead_m": ("Where the controller reads the chosen lane.", "0..40"),
    "estimation.mmae_prior": ("The MMAE's probabilities before the reference has spoken: "
                              "uniform (the paper's; paper mode keeps it), or each model's in "
                              "proportion to the inverse of its measured offset variance at "
                              "offset_lookahead_m (its tracker's R).", _one_of(MMAE_PRIORS)),
    "estimation.reference_std_m": ("The rear reference's offset noise in the MMAE's residual "
                                   "density (eq. 8's R): smaller moves the probabilities "
                                   "faster, and with the reference's own errors.", "0.001..1"),
    "estimation.reference_width_tolerance_m": (
        "A rear reading whose lane is further than this from the width the front detectors "
        "measure is taken as missed (it read a wrong line); paper mode compares every "
        "reading.", "0.01..10"),
    "estimation.output_at": ("Where the output offset is read: on the output lane at "
                             "offset_lookahead_m, or the selected model's own detection at its "
                             "nearest row (the paper's PID input; paper mode sets it).",
                             _one_of(OUTPUT_AT)),
    "estimation.mmae_input": ("What the MMAE compares with the reference: each model's Kalman "
                              "track, or its raw detection (the paper's; paper mode sets it).",
                              _one_of(MMAE_INPUTS)),
    "estimation.mmae_at_car": ("With detection input: compare the models and the reference at "
                               "the car (x = 0), the paper's offset of the vehicle, instead of "
                               "at each detector's own look-ahead.", "true, false"),
    "estimation.prefer_accepted": ("Prefer a model whose track accepted this step's detection "
                                   "over a likelier one whose track coasts (the paper takes "
                                   "the argmax; paper mode turns it off).", "true, false"),
    "estimation.lane_width_prior_m": ("Lane width that centres a one-boundary detection until "
                                      "the detectors have measured the width from two "
                                      "boundaries.", "1..10"),
    "estimation.lane_width_gain": ("Weight of each two-boundary width measurement in the "
                                   "running mean.", "(0, 1]"),
    "estimation.lane_width_range_m": ("Plausible lane widths [low, high]; measurements outside "
                                      "are ignored.", "0 < low < high"),
    "control": ("The controller, by name.", ""),
    "control.controller": ("Controller turning the estimated lane into steer and throttle.",
                           '"pid", "stanley", package.module:Class, entry points'),
    "sensors": ("Error magnitudes of the car's own sensors (sources: "
                "lanekeep/scenario/sensors.py).",
                ""),
    "sensors.perfect": ("Read the true values exactly (ablations).", "true, false"),
    "sensors.speed_scale_sigma": ("Wheel-speed scale error, 1-sigma, drawn once per episode.",
                                  f"0..{MAX_SPEED_SCALE_SIGMA:g}"),
    "sensors.speed_noise_mps": ("Wheel-speed noise per sample, 1-sigma.", ">= 0"),
    "sensors.speed_resolution_mps": ("Wheel-speed quantisation step (0.01 km/h).", ">= 0"),
    "sensors.gyro_noise_density_dps_rthz": ("Yaw-rate white noise density; + yaw = left.",
                                            ">= 0"),
    "sensors.gyro_bias_sigma_dps": ("Yaw-rate bias, 1-sigma, drawn per episode.", ">= 0"),
    "sensors.gyro_bias_walk_dps_rts": ("Random walk of the yaw-rate bias.", ">= 0"),
    "sensors.accel_noise_density_mps2_rthz": ("Accelerometer white noise density (150 "
                                              "ug/sqrt(Hz)).", ">= 0"),
    "sensors.steer_noise_deg": ("Steering-angle noise at the steering wheel; + = left.",
                                ">= 0"),
    "sensors.steer_resolution_deg": ("Steering-angle quantisation at the steering wheel.",
                                     ">= 0"),
    "sensors.steering_ratio": ("Steering wheel to road wheel, for the two keys above.",
                               "{:g}..{:g}".format(*STEERING_RATIO_RANGE)),
    "roadside": ("Props beside and over the road; all off by default, placed from the seed.",
                 ""),
    "roadside.guard_rail_sides": ("W-beam guard rail beyond the gravel.", _SIDES),
    "roadside.barrier_sides": ("Concrete (jersey) barrier beyond the gravel.",
                               _SIDES + "; not where a guard rail is"),
    "roadside.pole_spacing_m": ("Light poles every so many metres; 0 = none.", "0 or 10..500"),
    "roadside.pole_sides": ("Sides with light poles.", _SIDES),
    "roadside.signs_m": ("Roadside signs (right side) at these arc lengths.", "each >= 0"),
    "roadside.gantries_m": ("Overhead sign gantries at these arc lengths.", "each >= 0"),
    "roadside.overpasses_m": ("Bridges across the road (with their shadow band).",
                              "each >= 0"),
    "roadside.trees_per_100m": ("Trees per 100 m and side, 4..35 m beyond the gravel.",
                                "0..20"),
    "roadside.buildings_per_100m": ("Buildings per 100 m and side, 15..60 m beyond it.",
                                    "0..20"),
    "roadside.skyline": ("Far background: hills or buildings.", _one_of(SKYLINES)),
    "roadside.shadow_darkness": (
        "How dark the props' shadows are, as `conditions.shadows[].darkness`.", _UNIT),
    "traffic": ("Other vehicles drawn from the seed in the lanes beside the car's, never in "
                "its own; off by default.", ""),
    "traffic.vehicles_per_km": ("Vehicles per km of road in each lane but the car's; 0 = no "
                                "traffic.", f"0..{MAX_VEHICLES_PER_KM:g}"),
    "traffic.directions": ("Per lane, rightmost first: traffic driving the car's way or "
                           "towards it; empty = all the car's way.",
                           f"each of {_one_of(DIRECTIONS)}; empty or one per lane"),
    "traffic.speed_mps": ("Range each lane's speed is drawn from (one speed per lane, so "
                          "vehicles keep their gaps).", "[low, high], 0 <= low <= high <= 40"),
    "traffic.van_share": ("Share of vans among the vehicles.", _UNIT),
    "traffic.truck_share": ("Share of trucks among the vehicles.", "0..1, with vans at most 1"),
    "traffic.clear_m": ("No vehicle within this arc length of the car's start, in any lane.",
                        "0..200"),
    "criteria": ("Pass/fail limits of an episode; an episode that leaves the road or stops "
                 "early fails whatever they say.", ""),
    "criteria.max_lane_departures": ("Pass limit: times a wheel crossed an ego-lane boundary.",
                                     ">= 0; unset = not checked"),
    "criteria.max_car_lateral_error_m": ("Pass limit: the car's largest |true offset|.",
                                         "> 0; unset = not checked"),
    "criteria.max_fused_rmse_m": ("Pass limit: offset RMSE of the MMAE output.",
                                  "> 0; unset = not checked"),
    "criteria.bad_episode_fused_rmse_m": (
        "Not a pass limit: marks a two-mode scenario (markings hidden on some drives); an "
        "episode whose fused RMSE exceeds it is a bad episode, and the regression gate "
        "(`bench --baseline`) compares the rate of bad episodes instead of the RMSE.",
        "> 0; unset = one mode"),
    "criteria.margins": (
        "Not a pass limit: this scenario's margins of practical relevance for the regression "
        "gate (`bench --baseline`), each \"METRIC=ABS[,REL%]\" as `--margin` takes them "
        "(docs/statistics.md#margins); the command line's win.",
        "METRIC=ABS[,REL%] each"),
    "criteria.off_road_distance_m": ("End the episode as off road once the car's centre is "
                                     "this far from the ego lane's centre.",
                                     "> 0; unset = only when all wheels leave the pavement"),
}

# Units from the key's suffix (the project names units in keys), longest suffix first.
_SUFFIX_UNITS = (("_dps_rthz", "deg/s/sqrt(Hz)"), ("_dps_rts", "deg/s/sqrt(s)"),
                 ("_mps2_rthz", "m/s^2/sqrt(Hz)"), ("_per_100m", "per 100 m"),
                 ("_1pm", "1/m"), ("_mps", "m/s"), ("_dps", "deg/s"), ("_deg", "deg"),
                 ("_dn", "DN"), ("_m", "m"), ("_s", "s"))
_PIXELS = ("camera.width", "camera.height")

CONVENTIONS = """\
## Conventions

- **Road coordinates** (Frenet): `s` is the arc length along the road's centre line from its
  start, in metres; `r` is the lateral distance from it, **+ = left**.
- **Curvature**: **+ = turning left** (anticlockwise seen from above), **- = turning right**;
  radius = 1 / |curvature|.
- **Lanes and boundaries count from the right**: `road.ego_lane = 0` is the **rightmost** lane;
  boundary 0 is the right edge line, boundary `n_lanes` the left one, and `[[road.markings]]`
  lists them rightmost first. The car drives towards increasing `s`; another vehicle with a
  negative speed drives towards decreasing `s` (oncoming).
- **Angles** are in degrees in the file; headings and yaw **+ = anticlockwise** (towards the
  left); camera pitch + = up.
- **Offsets** (`start.offset_m`, vehicles' `offset_m`, and the estimators' offsets): **+ =
  left** of the lane centre.
- Vehicle frame (detectors, estimators): x forward, y left, origin on the ground under the
  middle of the wheelbase.
- Reading is strict: an unknown key, a wrong type or a value outside its allowed range is an
  error naming the dotted key and the file. Integers are accepted where numbers are expected;
  booleans are never numbers. "not set" defaults are absent from the file (TOML has no null).
"""


def _type_name(tp) -> str:
    origin, args = typing.get_origin(tp), typing.get_args(tp)
    if origin in (typing.Union, types.UnionType):
        inner = [a for a in args if a is not type(None)]
        return " or ".join(_type_name(a) for a in inner) + " (optional)"
    if origin is tuple:
        if len(args) == 2 and args[1] is Ellipsis:
            return f"array of {_type_name(args[0])}s"
        return f"array of {len(args)} {_type_name(args[0])}s"
    return {str: "string", int: "integer", float: "number", bool: "boolean"}[tp]


def _value(value) -> str:
    if value is None:
        return "not set"
    if isinstance(value, bool):
        return str(value).lower()
    if isinstance(value, str):
        return f'"{value}"'
    if isinstance(value, float):
        return f"{value:g}"
    if isinstance(value, tuple):
        return "[" + ", ".join(_value(v) for v in value) + "]"
    return str(value)


def _unit(path: str) -> str:
    if path in _PIXELS:
        return "px"
    key = path.rsplit(".", 1)[-1]
    return next((unit for suffix, unit in _SUFFIX_UNITS if key.endswith(suffix)), "")


def _nested(tp) -> tuple[type | None, bool]:
    """(dataclass, is an array of tables) of a field type, or (None, False)."""
    if dataclasses.is_dataclass(tp):
        return tp, False
    args = typing.get_args(tp)
    if typing.get_origin(tp) is tuple and args and dataclasses.is_dataclass(args[0]):
        return args[0], True
    return None, False


def walk(cls: type = Scenario, prefix: str = "") -> Iterator[tuple[str, dataclasses.Field, object]]:
    """(dotted key, field, type) of every key a scenario file may hold, tables included,
    depth first in declaration order."""
    hints = typing.get_type_hints(cls)
    for f in dataclasses.fields(cls):
        if not f.metadata.get("toml", True):
            continue
        path, tp = prefix + f.name, hints[f.name]
        yield path, f, tp
        inner, many = _nested(tp)
        if inner is not None:
            yield from walk(inner, path + ("[]." if many else "."))


def missing_descriptions(cls: type = Scenario) -> list[str]:
    """Dotted keys of `cls` without an entry in DESCRIPTIONS (those nested tables without one
    as well)."""
    return [path for path, _, _ in walk(cls) if path not in DESCRIPTIONS]


def stale_descriptions(cls: type = Scenario) -> list[str]:
    """DESCRIPTIONS entries that name no key of `cls`."""
    keys = {path for path, _, _ in walk(cls)}
    return sorted(set(DESCRIPTIONS) - keys)


def _default(f: dataclasses.Field) -> str:
    if f.default is not dataclasses.MISSING:
        return _value(f.default)
    if f.default_factory is not dataclasses.MISSING:
        return _value(f.default_factory())
    return "required"


def _row(path: str, f: dataclasses.Field, tp) -> str:
    text, allowed = DESCRIPTIONS.get(path, ("(undocumented)", ""))
    cells = [f"`{f.name}`", _type_name(tp), _unit(path), _default(f), allowed, text]
    return "| " + " | ".join(c.replace("|", "\\|") for c in cells) + " |"


def _section(title: str, note: str, rows: list[str]) -> list[str]:
    head = ["| key | type | unit | default | allowed | meaning |", "|---|---|---|---|---|---|"]
    return ["", f"## {title}", "", *([note, ""] if note else []), *head, *rows]


def render(cls: type = Scenario) -> str:
    """The whole reference as Markdown: the top-level keys, then one section per table."""
    sections: dict[str, tuple[str, str, list[str]]] = {"": ("Top level", "", [])}
    for path, f, tp in walk(cls):
        inner, many = _nested(tp)
        if inner is not None:
            name = path.replace("[]", "")
            text, allowed = DESCRIPTIONS.get(path, ("(undocumented)", ""))
            note = f"{text} How many: {allowed}." if many else text
            sections[path] = (f"[[{name}]]" if many else f"[{name}]", note, [])
            continue
        parent = path.rsplit(".", 1)[0].removesuffix("[]") if "." in path else ""
        sections[parent][2].append(_row(path, f, tp))
    lines = ["# Scenario file format", "",
             "<!-- Generated by `python -m lanekeep.scenario.reference -o "
             "docs/scenario_format.md` from lanekeep/scenario/schema.py; edit the descriptions in "
             "lanekeep/scenario/reference.py, not this file. -->", "",
             "A scenario is a TOML file (the shipped ones: `lanekeep/scenario/shipped/*.toml`; "
             "`lanekeep scenarios` lists them). Every key is optional unless its default says "
             "*required*.", "", CONVENTIONS.rstrip()]
    for title, note, rows in sections.values():
        lines += _section(title, note, rows)
    return "\n".join(lines) + "\n"


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(prog="python -m lanekeep.scenario.reference",
                                     description=__doc__.splitlines()[0])
    parser.add_argument("-o", "--output", type=Path, help="write here (default: stdout)")
    args = parser.parse_args(argv)
    text = render()
    if args.output is None:
        print(text, end="")
    else:
        args.output.write_text(text, encoding="utf-8")


if __name__ == "__main__":
    main()
