"""The simulator half of an episode: the world and what images and measures it.

`sense()` gives what the car's cameras and sensors produce this period (an `Observation`),
`actuate(command)` applies the car's command and advances the world one control period. The
world itself (the true pose, the MuJoCo state, the road, the scenario it was built from) stays
here and goes to scoring and recording only (lanekeep/loop/episode.py hands it on); what the
car is built from is its spec sheet (`car`, `cameras`, `distortions`), never the world.

Randomness: one generator per episode from the scenario's seed and name
(lanekeep/scenario/streams.py); the image effects draw from it, the sensors from a child
stream of their own, so that a perfect-sensor run sees the same frames, and the forward radar
from a second child (spawned after the sensors', so the frames and the other signals are the
same with or without it).
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from lanekeep.core.steps import Command, Observation
from lanekeep.core.timing import StageClock
from lanekeep.geometry.camera_model import CameraModel
from lanekeep.geometry.car import CarGeometry
from lanekeep.scenario.schema import Scenario
from lanekeep.scenario.streams import stream_entropy
from lanekeep.sensing.cameras import CameraRig, RenderSettings
from lanekeep.sensing.radar import Radar
from lanekeep.sensing.snapshot import make_effects
from lanekeep.sensing.vehicle_sensors import VehicleSensors
from lanekeep.world.build import World, build


class Simulator:
    """One scenario's world, its cameras with their image effects, and the car's sensors."""

    def __init__(self, scenario: Scenario, render_size: tuple[int, int] | None = None,
                 clock: StageClock | None = None) -> None:
        self.scenario = scenario
        self.world: World = build(scenario)
        self.period_s = scenario.control_period_s
        self.clock = clock or StageClock()
        width, height = render_size or (scenario.camera.width, scenario.camera.height)
        self.rig = CameraRig(self.world.model, RenderSettings.of(scenario, width, height))
        self._draw_streams()

    def _draw_streams(self) -> None:
        """The episode's generator and what keeps state across its periods (image effects,
        sensor biases), as at the start of the scenario's drive."""
        scenario = self.scenario
        # seed and name: scenarios on one seed draw independent noise (scenario/streams.py)
        self.rng = np.random.default_rng(stream_entropy(scenario))
        # One effects pipeline per camera: lens drops and the auto-exposure keep state.
        self.effects = make_effects(scenario, self.world, self.rig, self.rng)
        self.sensors = VehicleSensors(scenario.sensors, self.period_s, self.rng.spawn(1)[0])
        self.radar = Radar(self.world.model, scenario.sensors.radar, scenario.sensors.perfect,
                           self.rng.spawn(1)[0])
        # The radar serves the adaptive cruise (lanekeep/control/acc.py) and casts 145 rays a
        # period (about 1.5 ms): a car without the cruise (or in paper mode, which ignores it)
        # gets no readings (`radar` None in its signals).
        self.radar_on = scenario.control.acc and scenario.estimation.mode != "paper"

    def restart(self) -> None:
        """The same drive from its start: the car back at its start pose and speed, the other
        vehicles at time 0, the random streams and the effects' state anew (dm_control's
        `Task.initialize_episode` on the same physics)."""
        self.world.reset()  # as `build` leaves it (MuJoCo's reset puts the traffic's mocaps back)
        self._draw_streams()

    # -- the car's spec sheet ------------------------------------------------------------------
    @property
    def car(self) -> CarGeometry:
        return self.world.car.geometry

    @property
    def cameras(self) -> dict[str, CameraModel]:
        """The cameras' models at the frames' size (intrinsics and mounting)."""
        return dict(self.rig.cameras)

    @property
    def distortions(self) -> dict[str, np.ndarray | None]:
        """Per camera its lens coefficients (OpenCV), None for a pinhole."""
        return {name: self.rig.distortion(name) for name in self.rig.CAMERA_NAMES}

    # -- the period ----------------------------------------------------------------------------
    def sense(self) -> Observation:
        """The cameras' frames (the renderer and the image effects image the true scene;
        motion blur follows the true motion), then the sensors' signals with the radar's
        cycle, all of the world at one instant."""
        data, car = self.world.data, self.world.car
        frames = {}
        for name in self.rig.CAMERA_NAMES:
            depth = None
            if self.rig.settings.depth:
                rgb, depth = self.rig.render_rgb_depth(data, name)
            else:
                rgb = self.rig.render_rgb(data, name)
            self.clock.lap(f"render_{name}")
            frames[name] = self.effects[name](rgb, self.rng, speed_mps=car.speed_mps(),
                                              depth_m=depth, pose=car.pose())
            self.clock.lap(f"effects_{name}")
        signals = self.sensors.sample(car)
        if self.radar_on:
            signals = replace(signals, radar=self.radar.sample(data))
        self.clock.lap("sensors")
        return Observation(time_s=float(data.time), frames=frames, signals=signals)

    def actuate(self, command: Command) -> None:
        """Apply the command for one control period (lanekeep.world.build.SimulationError
        when the physics goes unstable). The clock's stages: "physics" (the car), "traffic"
        (the other vehicles' model and poses, the lamps' pools)."""
        self.world.step(command.steer, command.throttle, self.period_s, move_scene=False)
        self.clock.lap("physics")
        self.world.move_scene()
        self.clock.lap("traffic")

    # -- for the recording ---------------------------------------------------------------------
    def marking_masks(self) -> dict[str, np.ndarray]:
        """Per camera, the paint the camera can see now: the segmentation render's paint, less
        what fog or darkness hides (lanekeep/sensing/paint_visibility.py)."""
        world, masks = self.world, {}
        data = world.data
        for name in self.rig.CAMERA_NAMES:
            paint = world.marking_mask(self.rig.render_segmentation(data, name))
            bare, depth = self.rig.render_rgb_depth(data, name)
            masks[name] = self.effects[name].visible_paint(paint, bare, depth).astype(np.uint8)
        return masks

    def close(self) -> None:
        self.rig.close()
