"""Lane estimation: a Kalman tracker per detector and the MMAE selector over them."""

from lanekeep.estimators.kalman import LaneTracker, TrackerConfig, UpdateResult, UpdateStatus
from lanekeep.estimators.mmae import MMAE, MMAEConfig, MMAEOutput, apply_probability_floor
from lanekeep.estimators.reference import ReferenceRepair

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
