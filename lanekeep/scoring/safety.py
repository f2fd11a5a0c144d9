"""Safety among other vehicles, from one step's truth: the gap to the vehicle ahead in the car's
path, the time to collision (TTC) with it, contact between the car and any other vehicle, the
car's own longitudinal acceleration; and over an episode, their minima and counts
(`SafetyTally`).

Why: a car that keeps its lane perfectly may still tailgate, brake late or drive into a vehicle
that cuts in, and no lane metric sees it. The minimum TTC and the minimum gap are the classic
surrogate measures of traffic-conflict studies (Hayward 1972; Minderhoud and Bovy 2001); hard
braking events are how naturalistic-driving studies find near-misses in kinematics alone.

Geometry (the choices, and why each is close enough):
  - contact: an exact test of two oriented rectangles on the ground (the separating-axis test:
    two convex polygons are disjoint exactly when their projections on one of their edge
    normals are), the car's from its true pose and yaw, each vehicle's centred at its Frenet
    (s, r) and turned to the road's heading at s (+ pi when oncoming) plus its lane-change
    angle. Rectangles that only touch (an edge or a corner, no area in common, within
    TOUCH_M) are not in contact. A Frenet rectangle (s, r intervals) would be cheaper but
    turns each body with the road: on a 40 m radius its corners move ~10 cm, and it misses
    the corner-first contacts of a lane change.
  - the vehicle ahead: the nearest vehicle whose centre is ahead of the car's along the car's
    direction on the road and whose lateral extent (r interval) overlaps the car's, oncoming
    ones included (then the closing speed is the sum of the speeds). Each body's extents along
    s and r are those of its rectangle turned by its angle to the road (half extents
    L/2 |cos a| + W/2 |sin a| along, L/2 |sin a| + W/2 |cos a| across): exact for the
    rectangle's own bounding box in the road's frame, a few centimetres generous at the
    heading errors of lane keeping. The gap is bumper to bumper along the car's own line
    (constant r): the centreline's arc length between the two centres, turned into the length
    of the parallel line at the car's r exactly (ds - r * the road's turn in between), less
    both half extents. Parked vehicles (speed 0) count like any other.
  - TTC = gap / closing speed while closing (the car's velocity along the road minus the
    vehicle's, in the car's direction), infinite otherwise; 0 once the gap is gone.
  - the car's longitudinal acceleration: its true forward speed's change over the control
    period divided by the period. The free joint's acceleration of the last physics step
    (`Car.acceleration_body`) rings with the suspension on every bump; a period's mean is the
    kind of low-passed signal the braking thresholds below were defined on.

Hard braking: a deceleration of at least 0.4 g (3.92 m/s^2). Naturalistic-driving studies use
thresholds from about 0.25 g to 0.6 g (e.g. Accid. Anal. Prev. 132 (2019) 105267 compares
-0.25 to -0.6 g; the UDRIVE truck study, Jansen and Wesseling 2018, screens from 3.0 m/s^2
and compares up to 4.0 m/s^2+; Japanese studies between 0.2 g and 0.4 g, Naito et al. 2009),
0.4 g sits in the upper part, above what comfortable driving (about 2 m/s^2) and an adaptive
cruise's own comfort limit ask. One braking is one event: an event starts when the
deceleration reaches the threshold and ends only once it falls below the release level
(hysteresis), so a braking that wavers around 0.4 g counts once.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Protocol

import numpy as np

from lanekeep.geometry.road import Road

G_MPS2 = 9.80665
TOUCH_M = 1e-6  # rectangles overlapping by less than this (a micrometre) only touch


class VehicleTruth(Protocol):
    """What scoring reads of another vehicle at a step (lanekeep/traffic/state.py's
    VehicleState is one): its Frenet centre, size, speed along its direction of travel, that
    direction (+1 along s, -1 oncoming) and its angle to its lane (a lane change's)."""

    name: str
    s_m: float
    r_m: float
    speed_mps: float
    direction: int
    length_m: float
    width_m: float

    @property
    def heading_offset_rad(self) -> float: ...


# -- contact: oriented rectangles on the ground ---------------------------------------------
@dataclass(frozen=True)
class Footprint:
    """A body's rectangle on the ground: centre (world x, y), yaw, length along its yaw."""

    name: str
    x_m: float
    y_m: float
    yaw_rad: float
    length_m: float
    width_m: float

    def axes(self) -> tuple[np.ndarray, np.ndarray]:
        """Its forward and left unit vectors (its edges' directions and normals)."""
        c, s = math.cos(self.yaw_rad), math.sin(self.yaw_rad)
        return np.array([c, s]), np.array([-s, c])

    def corners(self) -> np.ndarray:
        """The four corners (4, 2), counter-clockwise from the front left."""
        forward, left = self.axes()
        centre = np.array([self.x_m, self.y_m])
        half_l, half_w = self.length_m / 2.0, self.width_m / 2.0
        return np.array([centre + half_l * forward + half_w * left,
                         centre - half_l * forward + half_w * left,
                         centre - half_l * forward - half_w * left,
                         centre + half_l * forward - half_w * left])

    def outline(self) -> np.ndarray:
        """The closed outline (5, 2), for drawing."""
        corners = self.corners()
        return np.vstack([corners, corners[:1]])


def footprints_overlap(a: Footprint, b: Footprint) -> bool:
    """Whether two rectangles share area (separating-axis test on their four edge normals);
    touching edges or corners (overlap under TOUCH_M) are not an overlap."""
    reach = math.hypot(a.length_m, a.width_m) / 2.0 + math.hypot(b.length_m, b.width_m) / 2.0
    if math.hypot(a.x_m - b.x_m, a.y_m - b.y_m) >= reach:  # circumscribed circles apart
        return False
    corners_a, corners_b = a.corners(), b.corners()
    for axis in (*a.axes(), *b.axes()):
        pa, pb = corners_a @ axis, corners_b @ axis
        if pa.max() <= pb.min() + TOUCH_M or pb.max() <= pa.min() + TOUCH_M:
            return False
    return True


def vehicle_footprints(road: Road, vehicles: Sequence[VehicleTruth]) -> tuple[Footprint, ...]:
    """Each vehicle's rectangle: centred at its Frenet (s, r), turned to the road's heading at
    s (+ pi when oncoming) plus its lane-change angle (one road look-up for all of them)."""
    if not vehicles:
        return ()
    s = np.array([v.s_m for v in vehicles], dtype=float)
    r = np.array([v.r_m for v in vehicles], dtype=float)
    xy = np.atleast_2d(road.position(s, r))
    heading = np.atleast_1d(road.heading_at(s))
    return tuple(
        Footprint(v.name, float(p[0]), float(p[1]),
                  float(h) + (math.pi if v.direction < 0 else 0.0) + v.heading_offset_rad,
                  v.length_m, v.width_m)
        for v, p, h in zip(vehicles, xy, heading, strict=True))


# -- the vehicle ahead ----------------------------------------------------------------------
@dataclass(frozen=True)
class PathBox:
    """A body in the road's frame: its centre (s, r), its half extents along s and across
    (of its rectangle turned by its angle to the road), its velocity along +s."""

    name: str
    s_m: float
    r_m: float
    half_length_m: float
    half_width_m: float
    velocity_s_mps: float

    @staticmethod
    def of(name: str, s_m: float, r_m: float, length_m: float, width_m: float,
           angle_rad: float, velocity_s_mps: float) -> PathBox:
        """`angle_rad`: the body's yaw relative to the road's tangent (either way along it)."""
        c, s = abs(math.cos(angle_rad)), abs(math.sin(angle_rad))
        return PathBox(name, s_m, r_m, length_m / 2.0 * c + width_m / 2.0 * s,
                       length_m / 2.0 * s + width_m / 2.0 * c, velocity_s_mps)


@dataclass(frozen=True)
class Lead:
    """The vehicle ahead in the car's path: bumper-to-bumper gap, closing speed, TTC."""

    name: str
    gap_m: float  # >= 0
    closing_speed_mps: float  # > 0 while the car closes on it
    ttc_s: float  # gap / closing speed while closing, else inf


def line_length(road: Road, s_from: float, ds: float, r_m: float) -> float:
    """Length of the road's parallel line at offset `r_m` from `s_from` forward by centreline
    arc `ds` (>= 0): ds - r * (the heading's turn in between), exact for any curvature; across
    the seam of a closed road the turn is taken in two pieces."""
    s_to = s_from + ds
    if road.closed and s_to > road.length_m:
        turn = (road.heading_at(road.length_m) - road.heading_at(s_from)
                + road.heading_at(s_to - road.length_m) - road.heading_at(0.0))
    else:
        turn = road.heading_at(s_to) - road.heading_at(s_from)
    return ds - r_m * float(turn)


def _signed_ds(road: Road, s_from: float, s_to: float) -> float:
    """s_to - s_from, the short way round on a closed road."""
    ds = s_to - s_from
    if road.closed:
        ds = (ds + road.length_m / 2.0) % road.length_m - road.length_m / 2.0
    return ds


def lead_vehicle(road: Road, car: PathBox, direction: int, vehicles: Sequence[PathBox]
                 ) -> Lead | None:
    """The nearest vehicle ahead of `car` (along `direction`, +1 = increasing s) whose lateral
    extent overlaps the car's, or None."""
    best: Lead | None = None
    for v in vehicles:
        ahead = _signed_ds(road, car.s_m, v.s_m) * direction
        if ahead <= 0.0 or abs(v.r_m - car.r_m) >= v.half_width_m + car.half_width_m:
            continue
        start = car.s_m if direction > 0 else car.s_m - ahead
        if road.closed:
            start %= road.length_m
        centres_m = line_length(road, start, ahead, car.r_m)
        gap = max(0.0, float(centres_m - car.half_length_m - v.half_length_m))
        if best is not None and gap >= best.gap_m:
            continue
        closing = float(direction * (car.velocity_s_mps - v.velocity_s_mps))
        ttc = (gap / closing) if closing > 0.0 else math.inf
        best = Lead(v.name, gap, closing, ttc)
    return best


# -- one step ----------------------------------------------------------------------------
@dataclass(frozen=True)
class StepSafety:
    """A step's safety truth (after its control period). Without other vehicles: no lead,
    no contact, the car's acceleration only."""

    accel_mps2: float = 0.0  # the car's longitudinal acceleration over the period (+ = faster)
    lead: str = ""  # the vehicle ahead in the car's path ("": none)
    gap_m: float | None = None  # bumper to bumper to it (None: no vehicle ahead)
    closing_speed_mps: float | None = None  # + while closing on it (None: no vehicle ahead)
    ttc_s: float = math.inf  # gap / closing speed while closing, else inf
    collided_with: str = ""  # a vehicle whose footprint overlaps the car's ("": none)
    vehicles: tuple[Footprint, ...] = ()  # every other vehicle's footprint (for drawing)


def step_safety(road: Road, pose: tuple[float, float, float], s_m: float, r_m: float,
                speed_mps: float, car_size_m: tuple[float, float], accel_mps2: float,
                vehicles: Sequence[VehicleTruth]) -> StepSafety:
    """The safety truth of the car at `pose` (its Frenet `s_m`, `r_m`; forward `speed_mps`;
    (length, width)) among `vehicles`."""
    if not vehicles:
        return StepSafety(accel_mps2=accel_mps2)
    length, width = car_size_m
    x, y, yaw = pose
    angle = (yaw - float(road.heading_at(s_m)) + math.pi) % (2.0 * math.pi) - math.pi
    direction = 1 if math.cos(angle) >= 0.0 else -1
    car = PathBox.of("car", s_m, r_m, length, width, angle, speed_mps * math.cos(angle))
    boxes = [PathBox.of(v.name, v.s_m, v.r_m, v.length_m, v.width_m, v.heading_offset_rad,
                        v.direction * v.speed_mps) for v in vehicles]
    lead = lead_vehicle(road, car, direction, boxes)
    footprints = vehicle_footprints(road, vehicles)
    own = Footprint("car", x, y, yaw, length, width)
    reach = math.hypot(length, width) / 2.0  # no rectangle farther than the half diagonals
    near = [f for f in footprints                # apart can touch: the test runs on these
            if math.hypot(f.x_m - x, f.y_m - y) <= reach + math.hypot(f.length_m, f.width_m) / 2]
    hit = next((f.name for f in near if footprints_overlap(own, f)), "")
    return StepSafety(accel_mps2=accel_mps2, lead=lead.name if lead else "",
                      gap_m=lead.gap_m if lead else None,
                      closing_speed_mps=lead.closing_speed_mps if lead else None,
                      ttc_s=lead.ttc_s if lead else math.inf, collided_with=hit,
                      vehicles=footprints)


def collision_reason(name: str, time_s: float) -> str:
    """The stop reason of an episode that ended in contact ("" when `name` is "")."""
    return f"collision with {name} at t = {time_s:.1f} s" if name else ""


# -- an episode ------------------------------------------------------------------------------
@dataclass(frozen=True)
class HardBraking:
    """A hard braking event: deceleration reaching `threshold_mps2` (0.4 g), over when it
    falls below `release_mps2` (0.2 g, about what comfortable braking uses)."""

    threshold_mps2: float = 0.4 * G_MPS2
    release_mps2: float = 0.2 * G_MPS2

    def __post_init__(self) -> None:
        if not 0.0 <= self.release_mps2 < self.threshold_mps2:
            raise ValueError(f"need 0 <= release_mps2 < threshold_mps2, got "
                             f"{self.release_mps2} and {self.threshold_mps2}")


class SafetyTally:
    """An episode's safety so far: minimum TTC and gap, hard braking events, collisions
    (counted when contact begins; an episode stops at its first, so 0 or 1 there)."""

    def __init__(self, braking: HardBraking | None = None) -> None:
        self.braking = braking or HardBraking()
        self.min_ttc_s = math.inf  # inf: never closing on a vehicle ahead
        self.min_gap_m: float | None = None  # None: never a vehicle ahead
        self.hard_braking_events = 0
        self.collisions = 0
        self._braking_now = False
        self._in_contact = False

    def add(self, step: StepSafety) -> None:
        self.min_ttc_s = min(self.min_ttc_s, step.ttc_s)
        if step.gap_m is not None:
            self.min_gap_m = step.gap_m if self.min_gap_m is None else min(self.min_gap_m,
                                                                           step.gap_m)
        self.add_acceleration(step.accel_mps2)
        contact = bool(step.collided_with)
        self.collisions += int(contact and not self._in_contact)  # counted on contact
        self._in_contact = contact

    def add_acceleration(self, accel_mps2: float) -> None:
        """One period's acceleration: a new event when the deceleration reaches the
        threshold outside an event; the event ends below the release level."""
        decel = -accel_mps2
        if not self._braking_now and decel >= self.braking.threshold_mps2:
            self.hard_braking_events += 1
            self._braking_now = True
        elif self._braking_now and decel < self.braking.release_mps2:
            self._braking_now = False
