"""Scripted traffic events, by vehicle name: what a test drive needs to happen at a known time
or place, whatever the car-following and lane-change models would have chosen."""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class CutIn:
    """`vehicle` changes into `to_lane` (the car's lane, typically) when the time reaches
    `at_time_s`, or, when that is None, once its rear is within `at_gap_m` ahead of the car's
    front (it must be ahead of the car). The change takes `duration_s` along a minimum-jerk
    path and is forced: neither MOBIL's incentive nor its safety check may refuse it."""

    vehicle: str
    to_lane: int
    at_time_s: float | None = None
    at_gap_m: float | None = None
    duration_s: float = 3.0


@dataclass(frozen=True)
class LeadBrake:
    """`vehicle` brakes at `decel_mps2` from `at_time_s` until its speed is `to_speed_mps`,
    then keeps that speed as its desired speed (IDM still keeps it off the one ahead). With
    `resume_after_s`, that long after it reached `to_speed_mps` it wants its own desired speed
    again (stop-and-go)."""

    vehicle: str
    at_time_s: float
    decel_mps2: float
    to_speed_mps: float = 0.0
    resume_after_s: float | None = None


TrafficEvent = CutIn | LeadBrake
