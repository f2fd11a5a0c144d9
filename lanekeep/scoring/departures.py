"""Lane departures and leaving the road, judged from where the car's tyres truly are: for
scoring and for ending an episode, never for perception or control."""

from __future__ import annotations

import numpy as np

from lanekeep.geometry.road import Road
from lanekeep.scoring.truth import frenet
from lanekeep.world.parts import WorldLayout


def wheels_outside_lane(road: Road, lane: int, tyres_xy: np.ndarray) -> bool:
    """Whether any tyre centre lies beyond lane `lane`'s boundaries."""
    _, r = frenet(road, tyres_xy)  # solved once for this and `off_road_reason`
    centre = road.lane_center_r(lane)
    return bool(np.any(np.abs(np.asarray(r) - centre) > road.lane_width_m / 2.0))


def off_road_reason(road: Road, layout: WorldLayout, tyres_xy: np.ndarray,
                    car_offset_m: float, limit_m: float | None, time_s: float) -> str:
    """Why the car has left the road ("" if it has not): all four wheels beyond the paved
    surface (the lanes and the asphalt shoulders the world laid with `layout`, or past the
    road's ends), or its centre more than `limit_m` from the ego lane's ([criteria]
    off_road_distance_m; None: no such limit)."""
    s, r = frenet(road, tyres_xy)
    s, r = np.asarray(s), np.asarray(r)
    lo = road.boundary_r(0) - layout.shoulder_m
    hi = road.boundary_r(road.n_lanes) + layout.shoulder_m
    off = (r < lo) | (r > hi)
    if not road.closed:
        off |= (s < -layout.lead_m) | (s > road.length_m + layout.lead_m)
    if np.all(off):
        return f"off road: all four wheels off the paved surface at t = {time_s:.1f} s"
    if limit_m is not None and abs(car_offset_m) > limit_m:
        return (f"off road: the car {abs(car_offset_m):.2f} m from the lane centre "
                f"(off_road_distance_m = {limit_m:g}) at t = {time_s:.1f} s")
    return ""
