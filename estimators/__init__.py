"""Lane estimation: a Kalman tracker per detector and the MMAE selector over them."""

from estimators.kalman import LaneTracker, TrackerConfig, UpdateResult, UpdateStatus
from estimators.mmae import MMAE, MMAEConfig, MMAEOutput, apply_probability_floor
from estimators.reference import ReferenceRepair

__all__ = [
    "MMAE",
    "LaneTracker",
    "MMAEConfig",
    "MMAEOutput",
    "ReferenceRepair",
    "TrackerConfig",
    "UpdateResult",
    "UpdateStatus",
    "apply_probability_floor",
]
