"""Everything the driver is built from, in one frozen value: the car's settings (estimation,
control, the control period, the speed it is asked to hold) and its spec sheet (the car's
dimensions, its cameras' models and lenses). Nothing of the world: no road, no conditions, no
simulator state, so whatever the driver computes it computes from what a car has.

`Scenario`'s estimation and control sections go in whole; what paper mode changes in them is
derived here (lanekeep/driver/paper_mode.py), once, so the driver never asks which mode it is
in."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np

from lanekeep.control.acc import AccSettings
from lanekeep.control.base import ControlContext
from lanekeep.detectors.config import DetectorsConfig
from lanekeep.detectors.registry import builtin_family, front_labels
from lanekeep.driver.paper_mode import estimator_settings, front_detector_config, roll_compensation
from lanekeep.estimators.lane_estimator import EstimatorSettings
from lanekeep.estimators.roll import RollCompensation
from lanekeep.geometry.camera_model import CameraModel
from lanekeep.geometry.car import CarGeometry
from lanekeep.scenario.estimation import EstimationConfig


@dataclass(frozen=True)
class DriverConfig:
    """The driver's settings and the car's spec sheet (see the module docstring)."""

    estimation: EstimationConfig
    controller: str  # [control] controller: "pid", "stanley", an entry point or an import path
    period_s: float  # the control period
    target_speed_mps: float
    car: CarGeometry
    cameras: Mapping[str, CameraModel]  # per camera name, its model at the frames' size
    distortions: Mapping[str, np.ndarray | None] = field(default_factory=dict)  # OpenCV lens
    acc: AccSettings | None = None  # the adaptive cruise ([control] acc); None: off
    detectors: DetectorsConfig | None = None  # the scenario's [detectors]; None: the shipped

    # -- what the settings imply (paper mode folded in) --------------------------------------
    @property
    def front_labels(self) -> list[str]:
        """The front models' labels (a plug-in given by import path: its own `name`)."""
        return front_labels(self.estimation.front_detectors)

    @property
    def families(self) -> dict[str, str]:
        """Per front label, the built-in whose measurements (paper mode's windows, the
        trackers' noise) it takes: its own name unless it subclasses a built-in."""
        return {label: builtin_family(name) or name
                for label, name in zip(self.front_labels, self.estimation.front_detectors,
                                       strict=True)}

    def front_detector_config(self, label: str) -> DetectorsConfig | None:
        """The detectors config front model `label` runs with (None: the shipped one)."""
        return front_detector_config(self.families[label], self.estimation.mode,
                                     base=self.detectors, keeps=self.estimation.paper_keeps)

    @property
    def estimator(self) -> EstimatorSettings:
        return estimator_settings(self.estimation)

    @property
    def roll(self) -> RollCompensation:
        return roll_compensation(self.estimation)

    @property
    def control(self) -> ControlContext:
        """What the controller is built from."""
        est = self.estimation
        mode = "paper" if est.runs_paper("controller") else "default"
        return ControlContext(self.period_s, self.target_speed_mps, self.car.wheelbase_m,
                              self.car.max_steer_rad, est.control_lookahead_m, mode,
                              self.acc)

    @property
    def odometry_lever_m(self) -> float:
        """Dead reckoning's reference point ahead of the rear axle: the middle of the
        wheelbase, the vehicle frame's origin (lanekeep/world/vehicle.py)."""
        return self.car.wheelbase_m / 2.0
