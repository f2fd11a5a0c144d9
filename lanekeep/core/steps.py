"""The two things that cross between the simulator and the car each control period: what the
car senses (`Observation`) and what it commands (`Command`). They sit in the lowest layer so
that the simulator (lanekeep/sensing/simulator.py), the driver (lanekeep/driver/) and the
recorder can all name them without importing one another."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from lanekeep.core.signals import VehicleSignals


@dataclass(frozen=True)
class Observation:
    """One control period's input to the car: its camera frames (RGB uint8 per camera name)
    and its own sensors' signals, taken at `time_s` on the car's clock."""

    time_s: float
    frames: Mapping[str, np.ndarray]
    signals: VehicleSignals


@dataclass(frozen=True)
class Command:
    """What the car asks of its actuators for one period: steer in [-1, 1] (+ = left, 1 = full
    lock) and throttle in [-1, 1] (- = brake)."""

    steer: float
    throttle: float
