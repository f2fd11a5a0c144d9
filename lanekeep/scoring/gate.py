"""The one gate to the simulator's truth.

An `Episode` (lanekeep/loop/episode.py) keeps its world and scenario behind one `Truth` and
hands it (or the part each needs) to what may see the truth: scoring, the recorder, the
vehicle sensors (they measure the true state) and the renderer and image effects (they image
the scene). Perception, estimation and control are built from what a car has (its camera
models, its estimation and control settings, its spec sheet) and are handed frames, sensor
signals and estimates, never this object: they cannot reach the car's true pose, the MuJoCo
state, the road geometry or the scenario's conditions by construction.
tests/loop/test_honest_loop.py proves it in both modes.

A gate, not a checker: reads through it cost an attribute lookup, nothing more, so the loop
is no slower for it.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

if TYPE_CHECKING:
    import mujoco

    from lanekeep.geometry.road import Road
    from lanekeep.scenario.schema import Scenario
    from lanekeep.scoring.safety import VehicleTruth
    from lanekeep.world.build import World
    from lanekeep.world.parts import ConditionsInfo, WorldLayout
    from lanekeep.world.vehicle import Car


class Truth:
    """The simulator's truth of one episode: its world (MuJoCo model and state, the car, the
    road, what the conditions laid) and the scenario it was built from."""

    __slots__ = ("scenario", "world")

    def __init__(self, world: World, scenario: Scenario) -> None:
        self.world = world
        self.scenario = scenario

    @property
    def road(self) -> Road:
        return self.world.road

    @property
    def car(self) -> Car:
        return self.world.car

    @property
    def data(self) -> mujoco.MjData:
        return self.world.data

    @property
    def model(self) -> mujoco.MjModel:
        return self.world.model

    @property
    def layout(self) -> WorldLayout:
        return self.world.layout

    @property
    def conditions(self) -> ConditionsInfo | None:
        """What the scenario's conditions put in the world (shadows, puddles, traffic)."""
        return self.world.conditions

    @property
    def lane(self) -> int:
        """The index of the lane the car is meant to keep (the scenario's ego lane)."""
        return self.scenario.road.ego_lane

    def vehicles(self) -> tuple[VehicleTruth, ...]:
        """The other vehicles now (lanekeep/traffic/state.py's VehicleState each, after the
        world's last step): `World.traffic`'s states, none when the scenario has no other
        vehicles (`World.traffic` None, or a world built before traffic drove)."""
        traffic = getattr(self.world, "traffic", None)
        return () if traffic is None else tuple(traffic.states)

    def pose(self) -> tuple[float, float, float]:
        """The car's true world pose (x, y, yaw)."""
        return self.world.car.pose()

    def time_s(self) -> float:
        return float(self.world.data.time)
