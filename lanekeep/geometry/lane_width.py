"""The width of a lane as the car believes it before it has measured one, held once.

Motorway lanes are 3.5-3.75 m wide (EU roads mostly 3.5-3.75 m, US Interstates 12 ft = 3.66 m);
3.7 m sits in that band. The detectors' ego-lane rules (detectors/config.py `LaneRules`) and the
estimator's prior for centring a one-boundary detection (estimators/settings.py) both read this
belief. It is not the simulated road's width: that is the scenario's `road.lane_width_m`
(default lanekeep/geometry/road.py `DEFAULT_LANE_WIDTH_M`), the truth only scoring reads,
which a scenario may make anything.
"""

from __future__ import annotations

LANE_WIDTH_PRIOR_M = 3.7  # m; the common width of motorway lanes, not any one road's
