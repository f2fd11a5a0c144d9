"""Lane estimation: a Kalman tracker per detector, the MMAE over them, and the estimator that
runs both for the closed loop (lane_estimator.py) with its settings (settings.py).

The names below load on first use, so that importing `lanekeep.estimators.settings` (as every
scenario does) does not import filterpy and scipy.
"""

from importlib import import_module

_EXPORTS = {
    "LaneTracker": "kalman", "TrackerConfig": "kalman", "UpdateResult": "kalman",
    "UpdateStatus": "kalman", "MMAE": "mmae", "MMAEConfig": "mmae", "MMAEOutput": "mmae",
    "apply_probability_floor": "mmae", "ReferenceRepair": "reference",
}
__all__ = sorted(_EXPORTS)


def __getattr__(name: str):
    if name in _EXPORTS:
        return getattr(import_module(f"{__name__}.{_EXPORTS[name]}"), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
