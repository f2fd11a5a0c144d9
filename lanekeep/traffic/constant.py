"""The traffic of before IDM: each vehicle at its constant speed along its lane, through
everything (`[traffic] model = "constant"`). Kept so that older drives can be replayed, and
given the flow's interface so that the world moves, and scoring reads, either kind alike."""

from __future__ import annotations

from collections.abc import Sequence

from lanekeep.traffic.state import EgoState, VehicleSetup, VehicleState


class ConstantFlow:
    """s(t) = s_m + direction * speed * t for every vehicle; r stays where it started."""

    def __init__(self, lane_centres_m: Sequence[float], road_length_m: float, closed: bool,
                 vehicles: Sequence[VehicleSetup]) -> None:
        self._centres = tuple(lane_centres_m)
        self._length_m = road_length_m
        self._closed = closed
        self._setups = tuple(vehicles)
        self._time_s = 0.0
        self._snapshot: tuple[float, tuple[VehicleState, ...]] | None = None  # (time, states)

    def reset(self) -> None:
        self._time_s = 0.0

    @property
    def time_s(self) -> float:
        return self._time_s

    def step(self, dt_s: float, ego: EgoState | None = None) -> None:
        """Advance the clock; the car changes nothing here."""
        if dt_s < 0.0:
            raise ValueError(f"dt_s must be >= 0, got {dt_s}")
        self._time_s += dt_s

    @property
    def states(self) -> tuple[VehicleState, ...]:
        """Every vehicle now (made once per time: the world and scoring both read them)."""
        if self._snapshot is None or self._snapshot[0] != self._time_s:
            self._snapshot = (self._time_s, tuple(self._state(v) for v in self._setups))
        return self._snapshot[1]

    def state(self, name: str) -> VehicleState:
        for v, state in zip(self._setups, self.states, strict=True):
            if v.name == name:
                return state
        raise KeyError(name)

    def _state(self, v: VehicleSetup) -> VehicleState:
        s = v.s_m + v.direction * v.speed_mps * self._time_s
        if self._closed:
            s %= self._length_m
        r = v.r_m if v.r_m is not None else self._centres[v.lane] + v.offset_m
        return VehicleState(name=v.name, s_m=s, r_m=r, speed_mps=v.speed_mps,
                            direction=v.direction, lane=v.lane, length_m=v.length_m,
                            width_m=v.width_m)
