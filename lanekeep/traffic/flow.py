"""Traffic on a road's lanes: every vehicle follows its leader by the IDM, changes lane by MOBIL
along a minimum-jerk path, and obeys the scenario's scripted events.

Deterministic and stateful: nothing is drawn here (a scenario draws its vehicles from its seed
before it builds the flow), so the same vehicles and the same calls give the same states, and
`reset()` returns to the start exactly.

Rules the models need that their papers leave to the simulation:

- Lanes. Lane k (0 = rightmost) has its centre at Frenet r = lane_centres_m[k] and its traffic
  drives in lane_directions[k] (+1 along s, -1 oncoming). "Ahead" in a lane is along its
  direction; on a closed road (a ring) s wraps and the foremost vehicle follows the last one
  across the wrap, on an open road it has a free road.
- Who is in a lane. A body is in every lane its lateral extent (r +- width / 2) overlaps by
  more than OVERLAP_MARGIN_M; a driving vehicle is also always in its own lane, and while it
  changes lane it is in both the lane it leaves and its target until the change completes: a
  leader for the followers of both, and it follows whichever of the two leaders asks it to
  brake more (the lower IDM acceleration).
- Gaps are bumper to bumper: the centres' distance along the lane less the two half lengths.
  A leader that drives the other way (the car straying into an oncoming lane) counts as one
  standing still.
- The ego car is in the lanes its extent overlaps: the others follow it, and MOBIL counts it
  as a new or old follower or a new leader. The flow never moves it, and it is not driven by
  the IDM; where MOBIL needs its acceleration, that is the IDM's with default IdmParams at its
  speed (a typical driver's reaction), for its safety criterion as for the incentive.
- Parked vehicles stand still at their place, no IDM, no lane change; they matter only in a
  lane they overlap by more than OVERLAP_MARGIN_M (a car stopped half on the shoulder), where
  they are standing obstacles that the lane's traffic stops behind. Their `lane` in the
  states is the lane they overlap most, -1 when they stand clear of every lane.
- MOBIL: a vehicle with `mobil` set weighs the adjacent lanes of its own direction (never an
  oncoming lane) every decision_interval_s, at times staggered by its index so that the
  vehicles do not all decide in one step, never while it changes and never within
  change_cooldown_s of the end of its last change, and never into one of no_entry_lanes
  (the ego car's lane, typically: there only a scripted cut-in enters). Beyond the paper's
  criteria a change needs room (both new gaps positive) and must be safe for the changer too
  (its own acceleration behind its new leader >= -b_safe): otherwise a vehicle already
  braking at the floor sees nothing to lose in a gap it cannot stop in. Its lane becomes the
  target at the start of the change.
"""

from __future__ import annotations

import bisect
import math
from collections.abc import Sequence
from dataclasses import replace

from lanekeep.traffic.events import CutIn, LeadBrake, TrafficEvent
from lanekeep.traffic.idm import IdmParams, free_road_acceleration, idm_acceleration
from lanekeep.traffic.lane_change import DEFAULT_CHANGE_DURATION_S, lateral_offset, lateral_speed
from lanekeep.traffic.mobil import incentive, safety_ok
from lanekeep.traffic.state import EgoState, VehicleSetup, VehicleState

__all__ = ["TrafficFlow"]

# A body is in a lane it overlaps by more than this (m): a wheel over the line is not yet a
# vehicle in that lane, a third of a metre across it is (and a parked car that far out blocks).
OVERLAP_MARGIN_M = 0.3
DECISION_INTERVAL_S = 1.0  # how often a MOBIL driver reconsiders its lane
CHANGE_COOLDOWN_S = 3.0  # no new change this soon after the end of the last one
EGO_IDM = IdmParams()  # the ego car's assumed reaction, for MOBIL only
# Event times compare with this slack, so that a time reached by summing steps (0.05 + ...)
# fires on the step it names, not one later.
TIME_EPS_S = 1e-9


class _Body:
    """One vehicle's mutable state, or the ego car's (refreshed every step)."""

    __slots__ = ("index", "name", "s", "v", "r", "dr", "acc", "length", "width", "direction",
                 "parked", "is_ego", "idm", "mobil", "offset", "lane", "from_lane", "changing",
                 "r0", "r1", "t0", "duration", "last_change_s", "next_decision_s", "brake",
                 "lanes", "resume_at_s", "resume_speed_mps")

    def __init__(self, index: int, name: str, length: float, width: float, direction: int):
        self.index, self.name = index, name
        self.length, self.width, self.direction = length, width, direction
        self.s = self.v = self.r = self.dr = self.acc = self.offset = 0.0
        self.parked = self.is_ego = self.changing = False
        self.idm: IdmParams = EGO_IDM
        self.mobil = None
        self.lane = self.from_lane = -1
        self.r0 = self.r1 = self.t0 = self.duration = 0.0
        self.last_change_s = -math.inf
        self.next_decision_s = math.inf
        self.brake: LeadBrake | None = None
        self.lanes: list[int] = []
        self.resume_at_s = math.inf  # a stop-and-go lead wants its speed again at this time
        self.resume_speed_mps = 0.0


class TrafficFlow:
    """The other vehicles on a road, stepped in time (see the module's rules).

    Args:
        lane_centres_m: Frenet r of each lane's centre, lane 0 (rightmost) first.
        lane_directions: +1 or -1 per lane, the direction its traffic drives.
        road_length_m: the road's length; on a closed road s wraps modulo it.
        closed: a ring (the last vehicle is the first one's leader across the wrap).
        vehicles: the vehicles at t = 0; states keep their order and names.
        events: scripted cut-ins and braking leads, by vehicle name.
        lane_width_m: for who overlaps which lane.
        change_duration_s: how long a MOBIL lane change takes (a cut-in has its own).
        no_entry_lanes: lanes MOBIL never changes into (scripted cut-ins still do).
        decision_interval_s: how often a MOBIL driver reconsiders its lane.
        change_cooldown_s: no MOBIL change this soon after the end of the last one.
    """

    def __init__(self, lane_centres_m: Sequence[float], lane_directions: Sequence[int],
                 road_length_m: float, closed: bool, vehicles: Sequence[VehicleSetup],
                 events: Sequence[TrafficEvent] = (), lane_width_m: float = 3.5,
                 change_duration_s: float = DEFAULT_CHANGE_DURATION_S, *,
                 no_entry_lanes: Sequence[int] = (),
                 decision_interval_s: float = DECISION_INTERVAL_S,
                 change_cooldown_s: float = CHANGE_COOLDOWN_S):
        self._centres = tuple(float(c) for c in lane_centres_m)
        self._directions = tuple(int(d) for d in lane_directions)
        self._length_m = float(road_length_m)
        self._closed = bool(closed)
        self._setups = tuple(vehicles)
        self._events = tuple(events)
        self._lane_width_m = float(lane_width_m)
        self._change_duration_s = float(change_duration_s)
        self._decision_interval_s = float(decision_interval_s)
        self._cooldown_s = float(change_cooldown_s)
        self._no_entry = frozenset(int(k) for k in no_entry_lanes)
        self._check_road()
        self._by_name = self._check_vehicles()
        self._event_vehicle = self._check_events()
        self.reset()

    # ----------------------------------------------------------------- construction checks

    def _check_road(self) -> None:
        if not self._centres or len(self._centres) != len(self._directions):
            raise ValueError(f"need one direction per lane: {len(self._centres)} lane centres, "
                             f"{len(self._directions)} directions")
        if any(d not in (1, -1) for d in self._directions):
            raise ValueError(f"lane directions must be +1 or -1, got {self._directions}")
        if any(b <= a for a, b in zip(self._centres, self._centres[1:], strict=False)):
            raise ValueError(f"lane centres must increase from lane 0 (rightmost) to the left, "
                             f"got {self._centres}")
        for name, value in (("road_length_m", self._length_m), ("lane_width_m",
                            self._lane_width_m), ("change_duration_s", self._change_duration_s),
                            ("decision_interval_s", self._decision_interval_s)):
            if not math.isfinite(value) or value <= 0.0:
                raise ValueError(f"{name} must be finite and > 0, got {value}")
        if any(not 0 <= k < len(self._centres) for k in self._no_entry):
            raise ValueError(f"no_entry_lanes {sorted(self._no_entry)} names a lane the road "
                             f"does not have ({len(self._centres)} lanes)")
        if not math.isfinite(self._cooldown_s) or self._cooldown_s < 0.0:
            raise ValueError(f"change_cooldown_s must be finite and >= 0, got {self._cooldown_s}")

    def _check_vehicles(self) -> dict[str, int]:
        by_name: dict[str, int] = {}
        n_lanes = len(self._centres)
        for i, v in enumerate(self._setups):
            if v.name in by_name:
                raise ValueError(f"two vehicles are named {v.name!r}")
            by_name[v.name] = i
            if v.direction not in (1, -1):
                raise ValueError(f"vehicle {v.name!r}: direction must be +1 or -1, "
                                 f"got {v.direction}")
            for field, value in (("s_m", v.s_m), ("speed_mps", v.speed_mps),
                                 ("offset_m", v.offset_m), ("length_m", v.length_m),
                                 ("width_m", v.width_m)):
                if not math.isfinite(value):
                    raise ValueError(f"vehicle {v.name!r}: {field} must be finite, got {value}")
            if v.speed_mps < 0.0 or v.length_m <= 0.0 or v.width_m <= 0.0:
                raise ValueError(f"vehicle {v.name!r}: needs speed >= 0 and a positive size")
            if v.parked and v.r_m is not None:
                continue  # placed by r; its lane number is not read
            if not 0 <= v.lane < n_lanes:
                raise ValueError(f"vehicle {v.name!r}: lane {v.lane} is not one of the "
                                 f"{n_lanes} lanes")
            if not v.parked and v.direction != self._directions[v.lane]:
                raise ValueError(f"vehicle {v.name!r} drives in direction {v.direction} in lane "
                                 f"{v.lane}, whose traffic drives {self._directions[v.lane]}")
        return by_name

    def _check_events(self) -> list[int]:
        indices = []
        for event in self._events:
            if event.vehicle not in self._by_name:
                raise ValueError(f"event {event!r} names no vehicle of the flow")
            i = self._by_name[event.vehicle]
            setup = self._setups[i]
            if setup.parked:
                raise ValueError(f"event {event!r}: vehicle {setup.name!r} is parked")
            if isinstance(event, CutIn):
                lane = event.to_lane
                if not 0 <= lane < len(self._centres) or \
                        self._directions[lane] != setup.direction:
                    raise ValueError(f"event {event!r}: lane {lane} is not a lane of the "
                                     f"vehicle's direction")
                if event.at_time_s is None and event.at_gap_m is None:
                    raise ValueError(f"event {event!r}: needs at_time_s or at_gap_m")
                if not event.duration_s > 0.0:
                    raise ValueError(f"event {event!r}: duration_s must be > 0")
            elif isinstance(event, LeadBrake):
                if not event.decel_mps2 > 0.0 or not event.to_speed_mps >= 0.0:
                    raise ValueError(f"event {event!r}: needs decel_mps2 > 0, to_speed_mps >= 0")
            else:
                raise ValueError(f"unknown traffic event {event!r}")
            indices.append(i)
        return indices

    # ----------------------------------------------------------------------- public API

    def reset(self) -> None:
        """Back to t = 0, every vehicle as set up, every event pending."""
        self._time_s = 0.0
        n = len(self._setups)
        self._bodies = [self._initial_body(i, setup, n) for i, setup in enumerate(self._setups)]
        self._moving = [b for b in self._bodies if not b.parked]
        self._ego_body = _Body(n, "ego", 1.0, 1.0, 1)
        self._ego_body.is_ego = True
        self._ego_present = False
        self._fired = [False] * len(self._events)
        self._keys: list[list[tuple[float, int]]] = [[] for _ in self._centres]
        self._snapshot: tuple[VehicleState, ...] | None = None

    @property
    def time_s(self) -> float:
        """Seconds since the start (the sum of the steps)."""
        return self._time_s

    @property
    def states(self) -> tuple[VehicleState, ...]:
        """Every vehicle now, in the order they were given."""
        if self._snapshot is None:
            self._snapshot = tuple(self._state_of(b) for b in self._bodies)
        return self._snapshot

    def state(self, name: str) -> VehicleState:
        """The named vehicle now."""
        if name not in self._by_name:
            raise KeyError(f"no vehicle named {name!r}")
        return self.states[self._by_name[name]]

    def step(self, dt_s: float, ego: EgoState | None = None) -> None:
        """Advance every vehicle by `dt_s` seconds around the ego car as it is now (None: no
        ego). All accelerations come from the state at the start of the step (a simultaneous
        update); speeds and positions follow the ballistic update that Treiber and Kanagaraj
        (2015, Physica A 419, 183) recommend, v += a dt, s += v dt + a dt^2 / 2, except that a
        vehicle stopping within the step stops there (speeds never go negative). dt_s = 0
        changes nothing."""
        if not math.isfinite(dt_s) or dt_s < 0.0:
            raise ValueError(f"dt_s must be finite and >= 0, got {dt_s}")
        if dt_s == 0.0:
            return
        t = self._time_s
        self._place_ego(ego)
        self._index_lanes()
        self._fire_events(t)
        self._decide_lane_changes(t)
        accelerations = [self._acceleration(b) for b in self._moving]
        t_new = t + dt_s
        for b, acc in zip(self._moving, accelerations, strict=True):
            self._advance(b, acc, dt_s, t_new)
        self._time_s = t_new
        self._snapshot = None

    # ----------------------------------------------------------------------- set-up

    def _initial_body(self, i: int, setup: VehicleSetup, n: int) -> _Body:
        b = _Body(i, setup.name, setup.length_m, setup.width_m, setup.direction)
        b.s = setup.s_m % self._length_m if self._closed else setup.s_m
        b.offset = setup.offset_m
        if setup.parked:
            b.parked = True
            b.r = setup.r_m if setup.r_m is not None else self._centres[setup.lane] + b.offset
            b.lane = self._parked_lane(b.r, b.width)
            return b
        b.v = setup.speed_mps
        b.r = self._centres[setup.lane] + b.offset
        b.lane = setup.lane
        b.idm = setup.idm
        b.mobil = setup.mobil
        if b.mobil is not None:  # staggered: vehicle i first decides at i / n of an interval
            b.next_decision_s = self._decision_interval_s * i / n
        return b

    def _parked_lane(self, r: float, width: float) -> int:
        overlaps = [(self._overlap(r, width, k), k) for k in range(len(self._centres))]
        best, lane = max(overlaps)
        return lane if best > OVERLAP_MARGIN_M else -1

    # ----------------------------------------------------------------------- lanes

    def _overlap(self, r: float, width: float, k: int) -> float:
        """How far (m) a body at r of this width reaches into lane k (negative: clear of it)."""
        half_lane = 0.5 * self._lane_width_m
        c = self._centres[k]
        return min(r + 0.5 * width, c + half_lane) - max(r - 0.5 * width, c - half_lane)

    def _lanes_of(self, b: _Body) -> list[int]:
        lanes = [k for k in range(len(self._centres))
                 if self._overlap(b.r, b.width, k) > OVERLAP_MARGIN_M]
        if b.parked or b.is_ego:
            return lanes
        own = (b.lane, b.from_lane) if b.changing else (b.lane,)
        return sorted(set(lanes).union(own))

    def _key(self, k: int, s: float) -> float:
        """Position along lane k's direction (on a ring, in [0, length))."""
        x = s if self._directions[k] > 0 else -s
        return x % self._length_m if self._closed else x

    def _place_ego(self, ego: EgoState | None) -> None:
        self._ego_present = ego is not None
        if ego is None:
            return
        e = self._ego_body
        e.s = ego.s_m % self._length_m if self._closed else ego.s_m
        e.r, e.v, e.length, e.width = ego.r_m, ego.speed_mps, ego.length_m, ego.width_m

    def _index_lanes(self) -> None:
        """Sort every lane's bodies along its direction, once a step."""
        keys: list[list[tuple[float, int]]] = [[] for _ in self._centres]
        bodies = self._bodies + [self._ego_body] if self._ego_present else self._bodies
        for b in bodies:
            b.lanes = self._lanes_of(b)
            for k in b.lanes:
                keys[k].append((self._key(k, b.s), b.index))
        for lane in keys:
            lane.sort()
        self._keys = keys

    def _body(self, index: int) -> _Body:
        return self._ego_body if index == len(self._bodies) else self._bodies[index]

    def _neighbours(self, k: int, x: float, index: int
                    ) -> tuple[_Body | None, float, _Body | None, float]:
        """The bodies just ahead of and just behind position x in lane k, along the lane's
        direction and leaving out body `index`, with their distances (m, centre to centre)."""
        keys = self._keys[k]
        lo = bisect.bisect_left(keys, (x, index))
        hi = lo + 1 if lo < len(keys) and keys[lo][1] == index else lo
        others = len(keys) - (hi - lo)
        if others == 0:
            return None, math.inf, None, math.inf
        ahead = behind = None
        dx_ahead = dx_behind = math.inf
        if self._closed:
            xa, ia = keys[hi % len(keys)]
            xb, ib = keys[(lo - 1) % len(keys)]
            ahead, dx_ahead = self._body(ia), (xa - x) % self._length_m
            behind, dx_behind = self._body(ib), (x - xb) % self._length_m
        else:
            if hi < len(keys):
                xa, ia = keys[hi]
                ahead, dx_ahead = self._body(ia), xa - x
            if lo > 0:
                xb, ib = keys[lo - 1]
                behind, dx_behind = self._body(ib), x - xb
        return ahead, dx_ahead, behind, dx_behind

    def _leader(self, b: _Body, k: int) -> tuple[_Body | None, float]:
        ahead, dx_ahead, behind, dx_behind = self._neighbours(k, self._key(k, b.s), b.index)
        if b.direction == self._directions[k]:
            return ahead, dx_ahead
        return behind, dx_behind  # in a lane of the other direction, its ahead is their behind

    # ----------------------------------------------------------------------- car following

    @staticmethod
    def _behind(follower: _Body, leader: _Body, dx: float) -> float:
        """The follower's IDM acceleration behind this leader, `dx` metres centre to centre."""
        gap = dx - 0.5 * (follower.length + leader.length)
        lead_speed = leader.v if leader.direction == follower.direction else 0.0
        return idm_acceleration(follower.idm, follower.v, gap, lead_speed)

    def _following(self, b: _Body) -> float:
        """IDM behind the leader that asks for the most braking, over the lanes it is in."""
        acc = math.inf
        for k in b.lanes:
            leader, dx = self._leader(b, k)
            if leader is not None:
                acc = min(acc, self._behind(b, leader, dx))
        return free_road_acceleration(b.idm, b.v) if math.isinf(acc) else acc

    def _acceleration(self, b: _Body) -> float:
        acc = self._following(b)
        if b.brake is not None:
            acc = min(acc, -b.brake.decel_mps2)
        return acc

    def _advance(self, b: _Body, acc: float, dt: float, t_new: float) -> None:
        """The ballistic update; a braking vehicle stops at 0, or at its LeadBrake's target
        speed while the brake (not its leader) sets its deceleration."""
        floor = 0.0
        if b.brake is not None and acc == -b.brake.decel_mps2:
            floor = b.brake.to_speed_mps
        v_new = b.v + acc * dt
        if acc < 0.0 and v_new < floor:
            t_stop = max(0.0, (b.v - floor) / -acc)  # it reaches the floor within the step
            ds = b.v * t_stop + 0.5 * acc * t_stop * t_stop + floor * (dt - t_stop)
            v_new = floor
        else:
            ds = b.v * dt + 0.5 * acc * dt * dt
        s = b.s + b.direction * ds
        b.s = s % self._length_m if self._closed else s
        b.acc = 0.0 if b.v == 0.0 and v_new == 0.0 else acc  # standing: the ground holds it
        b.v = v_new
        if b.brake is not None and v_new <= b.brake.to_speed_mps + 1e-9:
            self._hold(b, b.brake, t_new)
            b.brake = None
        if b.changing:
            elapsed = t_new - b.t0
            if elapsed >= b.duration - TIME_EPS_S:
                b.r, b.dr, b.changing, b.last_change_s = b.r1, 0.0, False, t_new
            else:
                b.r = lateral_offset(b.r0, b.r1, b.duration, elapsed)
                b.dr = lateral_speed(b.r0, b.r1, b.duration, elapsed)

    # ----------------------------------------------------------------------- lane changes

    def _start_change(self, b: _Body, lane: int, duration: float, t: float) -> None:
        """From its r now to the target lane's centre (plus its own offset); it is in both
        lanes from this step on."""
        b.from_lane, b.lane, b.changing = b.lane, lane, True
        b.r0, b.r1, b.t0, b.duration = b.r, self._centres[lane] + b.offset, t, duration
        if lane not in b.lanes:
            bisect.insort(self._keys[lane], (self._key(lane, b.s), b.index))
            b.lanes = sorted([*b.lanes, lane])

    def _decide_lane_changes(self, t: float) -> None:
        for b in self._moving:
            if b.mobil is None or t < b.next_decision_s - TIME_EPS_S:
                continue
            while b.next_decision_s <= t + TIME_EPS_S:
                b.next_decision_s += self._decision_interval_s
            if b.changing or t < b.last_change_s + self._cooldown_s - TIME_EPS_S:
                continue
            target = self._mobil_choice(b)
            if target is not None:
                self._start_change(b, target, self._change_duration_s, t)

    def _drives_in(self, b: _Body | None, k: int) -> bool:
        """Whether b is a driver whose braking MOBIL weighs in lane k (not parked, not
        oncoming there)."""
        return b is not None and not b.parked and b.direction == self._directions[k]

    def _mobil_choice(self, c: _Body) -> int | None:
        """The adjacent lane of its direction that MOBIL picks for c, or None to stay."""
        k = c.lane
        lead, dx_lead, old, dx_old = self._neighbours(k, self._key(k, c.s), c.index)
        own_before = self._following(c)
        old_before = old_after = 0.0
        if self._drives_in(old, k):
            old_before = self._behind(old, c, dx_old)
            old_after = (free_road_acceleration(old.idm, old.v) if lead is None or lead is old
                         else self._behind(old, lead, dx_old + dx_lead))
        best_gain, best_lane = -math.inf, None
        for k2 in (k - 1, k + 1):
            if (not 0 <= k2 < len(self._centres) or self._directions[k2] != c.direction
                    or k2 in self._no_entry):
                continue
            new_lead, dx_nl, new, dx_new = self._neighbours(k2, self._key(k2, c.s), c.index)
            if new_lead is not None and dx_nl - 0.5 * (c.length + new_lead.length) <= 0.0:
                continue  # no room beside it
            if new is not None and dx_new - 0.5 * (c.length + new.length) <= 0.0:
                continue
            own_after = (free_road_acceleration(c.idm, c.v) if new_lead is None
                         else self._behind(c, new_lead, dx_nl))
            new_before = new_after = 0.0
            if self._drives_in(new, k2):
                new_after = self._behind(new, c, dx_new)
                new_before = (free_road_acceleration(new.idm, new.v)
                              if new_lead is None or new_lead is new
                              else self._behind(new, new_lead, dx_new + dx_nl))
            if not (safety_ok(c.mobil, new_after) and safety_ok(c.mobil, own_after)):
                continue  # nor does it move in where it must itself brake harder than b_safe
            to_right = c.direction * (self._centres[k2] - self._centres[k]) < 0.0
            gain = incentive(c.mobil, own_before, own_after, new_before, new_after,
                             old_before, old_after, to_right)
            if gain > c.mobil.threshold_mps2 and gain > best_gain:
                best_gain, best_lane = gain, k2
        return best_lane

    # ----------------------------------------------------------------------- events

    @staticmethod
    def _hold(b: _Body, event: LeadBrake, t: float) -> None:
        """A braking lead reached its speed: it keeps it, and with `resume_after_s` wants its
        own desired speed again that long after (stop-and-go)."""
        b.idm = replace(b.idm, desired_speed_mps=event.to_speed_mps)
        if event.resume_after_s is not None:
            b.resume_at_s = t + event.resume_after_s

    def _fire_events(self, t: float) -> None:
        for b in self._bodies:
            if t >= b.resume_at_s - TIME_EPS_S:
                b.idm = replace(b.idm, desired_speed_mps=b.resume_speed_mps)
                b.resume_at_s = math.inf
        for i, event in enumerate(self._events):
            if self._fired[i]:
                continue
            b = self._bodies[self._event_vehicle[i]]
            if isinstance(event, LeadBrake):
                if t >= event.at_time_s - TIME_EPS_S:
                    self._fired[i] = True
                    b.resume_speed_mps = b.idm.desired_speed_mps
                    if b.v <= event.to_speed_mps:
                        self._hold(b, event, t)
                    else:
                        b.brake = event
            elif self._cut_in_due(event, b, t):
                self._fired[i] = True
                if b.lane != event.to_lane:  # (already there, or on its way: nothing to do)
                    self._start_change(b, event.to_lane, event.duration_s, t)

    def _cut_in_due(self, event: CutIn, b: _Body, t: float) -> bool:
        if event.at_time_s is not None:
            return t >= event.at_time_s - TIME_EPS_S
        if not self._ego_present:
            return False
        e = self._ego_body
        ds = b.s - e.s
        if self._closed:  # the nearer way round
            ds = (ds + 0.5 * self._length_m) % self._length_m - 0.5 * self._length_m
        return ds > 0.0 and ds - 0.5 * (b.length + e.length) <= event.at_gap_m

    # ----------------------------------------------------------------------- snapshots

    def _state_of(self, b: _Body) -> VehicleState:
        return VehicleState(name=b.name, s_m=b.s, r_m=b.r, speed_mps=b.v,
                            direction=b.direction, lane=b.lane, length_m=b.length,
                            width_m=b.width, accel_mps2=b.acc, lateral_speed_mps=b.dr,
                            changing_lane=b.changing)
