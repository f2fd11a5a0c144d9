"""Simulated forward radar: the object list an adaptive cruise's long-range radar gives its ECU.

Sampled once per control period, at the cameras' instant; figures from the data sheet of the
Continental ARS 408-21 (lanekeep/scenario/sensors.py `RadarConfig` cites them). What is
modelled:
  - Geometry: a horizontal fan of rays from the radar's phase centre (the site "radar" of
    mjcf/car.xml: front bumper, 0.5 m above the ground) cast with MuJoCo's ray caster
    (`mj_multiRay`, the `mj_ray` behind the <rangefinder> sensor: distance to the first geom
    surface, -1 for none). Rays 0.25 deg apart within the far scan (+-9 deg): at 250 m they
    are 1.1 m apart, so a 1.85 m wide car is hit by at least one ray to the sheet's full
    reach; 1 deg apart in the near scan (+-45 deg, 70 m: 1.2 m apart at its reach). The 145
    rays cost 0.7-1.9 ms a period in the shipped worlds (180-930 geoms), about what the
    period's 20 physics steps cost; as <rangefinder> sensors, which MuJoCo evaluates at every
    physics step, they would cost 20 times that (and be drawn into the camera images).
  - The rays are levelled (heading only, no pitch or roll): the sheet's elevation field of
    view (14 deg far, 20 deg near) is far wider than the body's pitch and roll (a few
    degrees), so a real beam keeps a target straight ahead when the car pitches under braking;
    one level fan at the mounting height stands for it, and never dips into a flat road.
  - What it sees: geoms of group 0 only (lanekeep/world/groups.py: the road, roadside props,
    other vehicles' bodies), never the car's own body. MuJoCo's rangefinder itself sees every
    group (only fully transparent geoms and the site's own body are skipped): it would range
    on paint and the contact plane (groups 1, 2), on segmentation-only paint (3) and on the
    translucent overlays of group 5 (shadows, puddles, snow, a lamp's glow 5 cm before a
    taillight). Returns less than GROUND_CLUTTER_M above the ground (the road is z = 0) are
    dropped as ground clutter: a speed bump (<= 0.15 m) is not a target.
  - Reach: a ray reports only between min_range_m and its scan's reach (the far reach within
    the far field of view, the near reach within the near one, the longer where both).
  - Objects, not rays: adjacent rays that hit the same body at ranges within CLUSTER_GATE_M
    of each other, all within OBJECT_EXTENT_M of the first, form one detection (a radar
    reports reflection points, not beam samples): its nearest ray's range, azimuth and range
    rate, one real point of the object. A car or truck seen from behind is one detection; a
    guard rail or a truck's long side is a row of them, as radars report such objects (a
    cluster's nearest range with its mean azimuth would put a guard rail that wraps round a
    bend's outside as a phantom straight ahead).
  - Range rate (Doppler): the relative velocity of the hit point projected on the ray. The
    hit body's point velocity comes from the change of the body's pose between two samples
    (a mocap vehicle is moved once a period, so this is its velocity over the last period;
    static geoms give zero), the radar's own from the car's true velocity and yaw rate now.
  - Noise (seeded, its own Generator): Gaussian on range, azimuth and range rate, one draw of
    three per detection in azimuth order; near-scan figures within near_range_m and the near
    field of view, far ones elsewhere; near azimuth noise grows linearly to the scan's edge.
Not modelled: radar cross-section and detection probability, the sheet's resolution (two
objects within 1.79 m and 1.6 deg far are one), multipath and ghost targets, the elevation
beam itself (nothing above or below the fan's level is seen), weather, latency, the sensor's
own tracking and classification. The first sample after a start has no previous poses to give
a Doppler, so it reports nothing (None), as a radar that has not finished its first cycle.

These reads of the simulator's truth (the MuJoCo state) all happen in `Radar.sample`; the car
receives only `RadarReading` (range, azimuth, range rate), never which body was hit.
"""

from __future__ import annotations

import math

import mujoco
import numpy as np

from lanekeep.core.signals import RadarDetection, RadarReading
from lanekeep.scenario.sensors import RadarConfig

SITE = "radar"  # mjcf/car.xml
CAR_BODY = "car"
CAR_JOINT = "car_root"
FAR_SPACING_DEG = 0.25
NEAR_SPACING_DEG = 1.0
SEEN_GROUPS = np.array([1, 0, 0, 0, 0, 0], dtype=np.uint8)  # geom group 0 only (see above)
GROUND_CLUTTER_M = 0.2
CLUSTER_GATE_M = 1.79  # the sheet's far range resolution: nearer steps are one surface
OBJECT_EXTENT_M = 2.6  # the widest vehicles (2.55 m, EU Directive 96/53/EC) are one object


def ray_azimuths(config: RadarConfig) -> tuple[np.ndarray, np.ndarray]:
    """The fan's azimuths (rad, ascending, + = left) and each ray's reach (m)."""
    far = config.far_half_fov_deg
    near = config.near_half_fov_deg if config.near_range_m > 0.0 else 0.0
    fine = np.arange(-far, far + 1e-9, FAR_SPACING_DEG)
    outer = np.arange(far + NEAR_SPACING_DEG, near + 1e-9, NEAR_SPACING_DEG)
    degrees = np.concatenate([-outer[::-1], fine, outer])
    inside_far = np.abs(degrees) <= far + 1e-9
    inside_near = np.abs(degrees) <= near + 1e-9
    reach = np.maximum(np.where(inside_far, config.far_range_m, 0.0),
                       np.where(inside_near, config.near_range_m, 0.0))
    return np.radians(degrees), reach


class Radar:
    """The car's forward radar for one episode; call `sample` once per control period.

    Random numbers come only from `rng` (three per detection; with `perfect` none).
    """

    def __init__(self, model: mujoco.MjModel, config: RadarConfig, perfect: bool,
                 rng: np.random.Generator) -> None:
        self.model = model
        self.config = config
        self.perfect = perfect
        self._rng = rng
        self._site = model.site(SITE).id
        self._car = model.body(CAR_BODY).id
        self._qvel = int(model.joint(CAR_JOINT).dofadr[0])
        self.mount_m = model.site_pos[self._site].copy()  # in the car's frame: its spec sheet
        self.azimuths_rad, self.reach_m = ray_azimuths(config)
        n = len(self.azimuths_rad)
        self._dist = np.zeros(n)
        self._geom = np.zeros(n, dtype=np.int32)
        self._previous: tuple[float, np.ndarray, np.ndarray] | None = None

    def reset(self) -> None:
        """Forget the previous poses: the next sample starts a new cycle (reports None)."""
        self._previous = None

    def sample(self, data: mujoco.MjData) -> RadarReading | None:
        """Cast the fan on the world as it is now and return what the radar reports."""
        hits = self._cast(data)
        now, poses = float(data.time), (data.xpos.copy(), data.xmat.copy())
        previous, self._previous = self._previous, (now, *poses)
        if previous is None or not now > previous[0]:
            return None
        rates = self._range_rates(data, hits, now - previous[0], previous[1], previous[2])
        detections = self._measure(self._clusters(hits), hits, rates)
        return RadarReading(tuple(sorted(detections, key=lambda d: d.range_m)),
                            float(self.mount_m[0]))

    # -- truth ---------------------------------------------------------------------------------
    def _cast(self, data: mujoco.MjData) -> dict[str, np.ndarray]:
        """Per ray that returns: index, range, unit direction, hit point, hit body."""
        rot = data.xmat[self._car].reshape(3, 3)
        heading = math.atan2(rot[1, 0], rot[0, 0])
        angles = heading + self.azimuths_rad
        dirs = np.stack([np.cos(angles), np.sin(angles), np.zeros_like(angles)], axis=1)
        origin = data.site_xpos[self._site].copy()
        mujoco.mj_multiRay(self.model, data, origin, dirs.ravel(), SEEN_GROUPS, 1, self._car,
                           self._geom, self._dist, None, len(angles), float(self.reach_m.max()))
        points = origin + self._dist[:, None] * dirs
        ok = ((self._geom >= 0) & (self._dist >= self.config.min_range_m)
              & (self._dist <= self.reach_m) & (points[:, 2] > GROUND_CLUTTER_M))
        index = np.flatnonzero(ok)
        return {"index": index, "range": self._dist[index].copy(), "dir": dirs[index],
                "point": points[index], "body": self.model.geom_bodyid[self._geom[index]]}

    def _range_rates(self, data: mujoco.MjData, hits: dict[str, np.ndarray], dt_s: float,
                     xpos_before: np.ndarray, xmat_before: np.ndarray) -> np.ndarray:
        """d(range)/dt of each hit: (hit point's velocity - radar's velocity) . ray."""
        body, point = hits["body"], hits["point"]
        rot_now = data.xmat[body].reshape(-1, 3, 3)
        rot_before = xmat_before[body].reshape(-1, 3, 3)
        local = np.einsum("nji,nj->ni", rot_now, point - data.xpos[body])  # in the body
        point_before = xpos_before[body] + np.einsum("nij,nj->ni", rot_before, local)
        target_mps = (point - point_before) / dt_s
        linear = data.qvel[self._qvel:self._qvel + 3]  # world frame
        angular = data.qvel[self._qvel + 3:self._qvel + 6]  # car frame
        rot_car = data.xmat[self._car].reshape(3, 3)
        radar_mps = linear + rot_car @ np.cross(angular, self.mount_m)
        return np.einsum("ni,ni->n", target_mps - radar_mps, hits["dir"])

    def _clusters(self, hits: dict[str, np.ndarray]) -> list[np.ndarray]:
        """Positions in `hits` grouped by adjacent rays on one body at a continuous range,
        each group no wider than an object."""
        index, rng_m, body, point = hits["index"], hits["range"], hits["body"], hits["point"]
        clusters: list[list[int]] = []
        for k in range(len(index)):
            if (clusters and index[k] == index[k - 1] + 1 and body[k] == body[k - 1]
                    and abs(rng_m[k] - rng_m[k - 1]) <= CLUSTER_GATE_M
                    and np.linalg.norm(point[k] - point[clusters[-1][0]]) <= OBJECT_EXTENT_M):
                clusters[-1].append(k)
            else:
                clusters.append([k])
        return [np.array(c) for c in clusters]

    # -- the sensor ----------------------------------------------------------------------------
    def _measure(self, clusters: list[np.ndarray], hits: dict[str, np.ndarray],
                 rates: np.ndarray) -> list[RadarDetection]:
        c = self.config
        noise = (np.zeros((len(clusters), 3)) if self.perfect
                 else self._rng.standard_normal((len(clusters), 3)))
        out = []
        for cluster, (n_range, n_azimuth, n_rate) in zip(clusters, noise, strict=True):
            nearest = cluster[np.argmin(hits["range"][cluster])]
            range_m = float(hits["range"][nearest])
            azimuth = float(self.azimuths_rad[hits["index"][nearest]])
            reach = float(self.reach_m[hits["index"][nearest]])
            near = (range_m <= c.near_range_m
                    and abs(azimuth) <= math.radians(c.near_half_fov_deg) + 1e-9)
            if near:
                edge = min(abs(math.degrees(azimuth)) / c.near_half_fov_deg, 1.0)
                azimuth_sigma_deg = (c.azimuth_sigma_near_deg
                                     + edge * (c.azimuth_sigma_near_edge_deg
                                               - c.azimuth_sigma_near_deg))
                range_sigma_m = c.range_sigma_near_m
            else:
                azimuth_sigma_deg, range_sigma_m = c.azimuth_sigma_far_deg, c.range_sigma_far_m
            out.append(RadarDetection(
                range_m=min(max(range_m + range_sigma_m * float(n_range), c.min_range_m), reach),
                azimuth_rad=azimuth + math.radians(azimuth_sigma_deg) * float(n_azimuth),
                range_rate_mps=float(rates[nearest]) + c.range_rate_sigma_mps * float(n_rate),
            ))
        return out
