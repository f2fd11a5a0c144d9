"""From LaneNet outputs to lanes: proposals, grouping by slot, a RANSAC parabola per boundary.

Proposals are the cells whose objectness exceeds a threshold: a point on a boundary (the cell's
band centre row, x from the offset head), a box around that piece of marking (one cell wide,
centred on the point, one band tall) and a confidence, which is what AP ranks.

Each slot's points are one boundary ("other" may hold several: fitted one after another on what
the previous fits left). The fit is RANSAC over a model linear in its parameters:
  - camera known: y(x) = c0 + c1 x + c2 x^2 on the ground (vehicle frame, metres), the points
    brought down with `CameraModel.pixels_to_ground`;
  - camera unknown: the same ground parabola seen by a level pinhole camera over a flat road. With
    d = v - v_h (rows below the horizon) the ground distance is x = k / d, so
    u = cx - fx y / x = A + B d + C / d: a curve with three linear parameters, and v_h is
    found where the boundaries' near parts meet (their vanishing point).
Residuals are in image pixels in both cases (ground residuals are divided by the metres one pixel
spans at that distance), so one threshold serves near and far points. RANSAC draws from a
generator seeded per call: the same outputs always give the same lanes.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass

import numpy as np

from lanekeep.detectors.base import LaneEstimate
from lanekeep.detectors.lanenet_targets import OTHER, SLOTS, CellGrid
from lanekeep.geometry.camera_model import CameraModel
from lanekeep.geometry.lane_poly import LanePoly

CURVATURE_PRIOR_PER_M = 0.002
UNSEEN_WEIGHT = 0.3  # 1 = paint ignored
WIDTH_STD_M = 0.15  # 0 = no width prior
SCORE_POWER = 2.0  # 0 = objectness does not weigh the ego pair's points
MAX_RANGE_M = 150.0  # ground points further ahead are not fitted
PRIOR_SHAPES = ("gaussian", "cauchy")
CURVATURE_PRIOR_SHAPE = "cauchy"
PAIR_PASSES = 10  # the ego pair's refits: inlier gate and prior weight settle within a few


@dataclass(frozen=True)
class DecodeSettings:
    """Thresholds of the decoding (tuned numbers belong in the detectors TOML)."""

    score_threshold: float = 0.5  # objectness probability of a proposal
    inlier_px: float = 6.0  # RANSAC residual threshold (frame pixels)
    iterations: int = 100
    min_points: int = 4  # a boundary needs at least this many inliers
    max_other: int = 3  # boundaries fitted from the "other" slot
    seed: int = 0  # of RANSAC's generator
    # Prior of a ground boundary's curvature (std, 1/m; 0 = none), weighed against its points'
    # pixel noise: points that end 10 m ahead hardly fix a parabola's bend, and without a prior
    # its extrapolation to 20 m can miss by metres (LaneNet's night FDE was 63 cm, its median
    # 6 cm). Chosen with its shape on the simulated validation split
    # (tools/tune_lanenet_decode.py --curvature 0.001,0.002,0.003 --score-power 2,4: Cauchy
    # 0.002, objective 32.76 cm; Gaussian 0.003, the earlier choice, 32.85, and 33.06 with
    # the ego pair's earlier three refits).
    curvature_prior_per_m: float = CURVATURE_PRIOR_PER_M
    # Its shape in the ego pair's fit. "gaussian" pulls every bend toward straight in
    # proportion to it, a sharp turn's most: points to 15-24 m fixed a 40 m radius turn's bend
    # at half its value, and the car cut the turn. "cauchy" (a Student t with one degree of
    # freedom, the same scale) pulls a bend within the scale as the Gaussian does and lets one
    # the points show clearly stand: roads are mostly straight, but a turn is a turn.
    curvature_prior_shape: str = CURVATURE_PRIOR_SHAPE
    pixel_noise_px: float = 2.0  # std of a proposal's x in frame pixels
    # A boundary point where the paint head sees no paint (behind a car, or guessed through the
    # dark) is inferred, not seen: its std is pixel_noise_px / max(paint, unseen_weight). The
    # ego pair's width is held to the lane's width with `width_std_m`, so that a side made of
    # inferred points follows the seen side (tools/tune_lanenet_decode.py, occluded split).
    unseen_weight: float = UNSEEN_WEIGHT
    width_std_m: float = WIDTH_STD_M
    # A point's weight in the ego pair's least squares (not in its inlier gate) is also its
    # objectness to this power (0 = the network's confidence ignored): a proposal the network
    # is unsure of is one whose place it is unsure of too (at night a dashed line's least
    # confident proposals lay furthest inside the lane). Chosen on the simulated validation
    # split (tools/tune_lanenet_decode.py --score-power 0,1,2,4: objective 35.93, 34.00,
    # 33.06, 33.19 cm). The weights are absolute: below 1 they also weaken the points against
    # the curvature prior (see docs/experiments.md, "tried and not kept").
    score_power: float = SCORE_POWER
    # Ground points further than this from the camera are not fitted (rows near the horizon
    # map to no usable ground beyond 150 m). Nearer limits were tried on the validation split
    # and not kept (tools/tune_lanenet_decode.py --max-range 20,30,45,150, Gaussian prior
    # 0.003, three refits: objective 34.74, 34.40, 33.74, 33.06 cm; 30 m fits the rendered
    # copy best, ADE 7.7 against 8.3 cm, but occluded frames need the far points, 27.2
    # against 25.1).
    max_range_m: float = MAX_RANGE_M

    def __post_init__(self) -> None:
        if not 0.0 < self.score_threshold < 1.0:
            raise ValueError("score_threshold must be in (0, 1)")
        if self.inlier_px <= 0 or self.iterations < 1 or self.min_points < 3:
            raise ValueError("inlier_px > 0, iterations >= 1, min_points >= 3")
        if self.curvature_prior_per_m < 0 or self.pixel_noise_px <= 0:
            raise ValueError("curvature_prior_per_m >= 0, pixel_noise_px > 0")
        if not 0.0 < self.unseen_weight <= 1.0 or self.width_std_m < 0:
            raise ValueError("unseen_weight in (0, 1], width_std_m >= 0")
        if not self.score_power >= 0.0:
            raise ValueError("score_power >= 0")
        if not self.max_range_m > 0.0:
            raise ValueError("max_range_m > 0")
        if self.curvature_prior_shape not in PRIOR_SHAPES:
            raise ValueError(f"curvature_prior_shape must be one of {PRIOR_SHAPES}")

    def curvature_prior_row(self, n_params: int) -> np.ndarray:
        """The prior as one more row of a fit weighted to pixels, the curvature term last:
        (c2 / sigma_c2)^2 beside residuals (px / pixel_noise)^2, c2 = curvature / 2. No row
        (shape (0, n)) without a prior."""
        if self.curvature_prior_per_m == 0:
            return np.zeros((0, n_params))
        row = np.zeros((1, n_params))
        row[0, -1] = self.pixel_noise_px / (self.curvature_prior_per_m / 2.0)
        return row


@dataclass(frozen=True)
class Proposals:
    """N proposals of one frame, frame pixels: points (N, 2), boxes (N, 4) x0 y0 x1 y1."""

    points_px: np.ndarray
    boxes_px: np.ndarray
    scores: np.ndarray
    slots: np.ndarray
    slot_probs: np.ndarray  # (N,) probability of the chosen slot
    paint: np.ndarray  # (N,) probability that paint is seen in the cell (1 without that head)


@dataclass(frozen=True)
class Boundary:
    """One fitted boundary: coefficients in `frame` ("ground": y(x) = c0 + c1 x + c2 x^2 in
    metres; "image": u(v) = c0 + c1 d + c2 / d with d = v - horizon_row), its inlier image
    points and, on the ground, their vehicle-frame points."""

    slot: int
    coeffs: np.ndarray
    frame: str
    points_px: np.ndarray
    score: float  # mean objectness of the inliers
    points_xy: np.ndarray | None = None
    horizon_row: float | None = None
    paint: np.ndarray | None = None  # each inlier's paint probability (Proposals.paint)
    scores: np.ndarray | None = None  # each inlier's objectness (Proposals.scores)

    @property
    def name(self) -> str:
        return SLOTS[self.slot]

    def x_at_rows(self, rows_px: np.ndarray, camera: CameraModel | None = None,
                  extend_rows: tuple[float, float] | None = None) -> np.ndarray:
        """Image x of the curve at each row (NaN off the curve's span; `extend_rows` = a row
        range to extend it over instead, e.g. the whole visible road)."""
        rows = np.asarray(rows_px, dtype=float)
        lo, hi = extend_rows or (self.points_px[:, 1].min(), self.points_px[:, 1].max())
        if self.frame == "image":
            d = rows - float(self.horizon_row)
            with np.errstate(divide="ignore", invalid="ignore"):
                x = self.coeffs[0] + self.coeffs[1] * d + self.coeffs[2] / d
            # u = A + B d + C / d turns back where d^2 = C / B: a boundary seen on one side
            # of that row does not continue beyond it (an extension would fold over the road).
            b_, c_ = float(self.coeffs[1]), float(self.coeffs[2])
            if b_ != 0.0 and c_ / b_ > 0.0:
                fold = float(np.sqrt(c_ / b_))
                seen = self.points_px[:, 1] - float(self.horizon_row)
                if np.median(seen) > fold:
                    lo = max(lo, float(self.horizon_row) + fold)
                else:
                    hi = min(hi, float(self.horizon_row) + fold)
        else:
            if camera is None:
                raise ValueError("a ground-plane boundary needs the camera to be drawn")
            xs = self.points_xy[:, 0]
            x_lo, x_hi = float(xs.min()), float(xs.max())
            if extend_rows is not None:  # from the camera to 1.5x the farthest point
                cam_x = float(camera.position_m[0])
                if np.mean(xs) > cam_x:
                    x_lo, x_hi = min(x_lo, cam_x), cam_x + 1.5 * (x_hi - cam_x)
                else:
                    x_lo, x_hi = cam_x + 1.5 * (x_lo - cam_x), max(x_hi, cam_x)
            g = np.linspace(x_lo, x_hi, 400)
            uv, ok = camera.project_ground(np.stack([g, LanePoly.of(self.coeffs).y(g)], -1))
            uv = uv[ok]
            uv = uv[np.argsort(uv[:, 1])]
            if len(uv) < 2:
                return np.full(rows.shape, np.nan)
            x = np.interp(rows, uv[:, 1], uv[:, 0], left=np.nan, right=np.nan)
        return np.where((rows >= lo) & (rows <= hi), x, np.nan)


def proposals(objectness: np.ndarray, x_offset: np.ndarray, slot_logits: np.ndarray,
              grid: CellGrid, score_threshold: float,
              marking_logits: np.ndarray | None = None) -> Proposals:
    """Proposals of one frame from its head outputs: objectness logits (rows, cols), offsets
    (rows, cols) in 0..1, slot logits (n_slots, rows, cols), paint logits (rows, cols)."""
    prob = 1.0 / (1.0 + np.exp(-np.asarray(objectness, dtype=np.float64)))
    r, c = np.nonzero(prob > score_threshold)
    paint = np.ones(len(r))
    if marking_logits is not None:
        paint = 1.0 / (1.0 + np.exp(-np.asarray(marking_logits, dtype=np.float64)[r, c]))
    x = grid.cell_to_x(c, x_offset[r, c])
    y = grid.row_centres()[r]
    logits = slot_logits[:, r, c].astype(np.float64)
    e = np.exp(logits - logits.max(axis=0, keepdims=True))
    p = e / e.sum(axis=0, keepdims=True)
    half_w, half_h = grid.cell_w / 2.0, grid.cell_h / 2.0
    boxes = np.stack([x - half_w, y - half_h, x + half_w, y + half_h], -1)
    return Proposals(np.stack([x, y], -1).reshape(-1, 2), boxes.reshape(-1, 4), prob[r, c],
                     p.argmax(axis=0).astype(np.int64), p.max(axis=0, initial=0.0), paint)


def ransac_fit(basis: np.ndarray, target: np.ndarray, scale: np.ndarray, threshold: float,
               iterations: int, rng: np.random.Generator, prior: np.ndarray | None = None
               ) -> tuple[np.ndarray, np.ndarray] | None:
    """RANSAC of target ~ basis @ c with 3-point samples; residual / scale compared with the
    threshold. Returns (coefficients refitted on the inliers, inlier mask) or None. `prior`:
    rows (k, 3) added, with target 0, to the refit's system weighted by 1 / scale."""
    prior = np.zeros((0, basis.shape[1])) if prior is None else prior
    n = len(target)
    if n < 3:
        return None
    # All hypotheses at once: (iterations, 3) distinct indices, one batched 3x3 solve.
    idx = np.argsort(rng.random((iterations, n)), axis=1)[:, :3]
    a, b = basis[idx], target[idx]
    ok = np.abs(np.linalg.det(a)) > 1e-12
    if not ok.any():
        return None
    c = np.linalg.solve(a[ok], b[ok][..., None])[..., 0]  # (K, 3)
    inl = np.abs(c @ basis.T - target) / scale < threshold  # (K, n)
    best = inl[int(np.argmax(inl.sum(axis=1)))]
    if best.sum() < 3:
        return None
    for _ in range(2):  # least squares on the consensus, then once more on its own inliers
        w = 1.0 / scale[best]
        c, *_ = np.linalg.lstsq(np.vstack([basis[best] * w[:, None], prior]),
                                np.concatenate([target[best] * w, np.zeros(len(prior))]),
                                rcond=None)
        refined = np.abs(basis @ c - target) / scale < threshold
        if refined.sum() < 3:
            break
        best = refined
    return c, best


def estimate_horizon_row(groups: list[np.ndarray], grid: CellGrid) -> float:
    """Row where the boundaries' near parts (straight lines u = a + b v through their lower
    half) meet; with fewer than two, one band above the highest proposal."""
    lines = []
    for pts in groups:
        if len(pts) < 3:
            continue
        lower = pts[pts[:, 1] >= np.median(pts[:, 1])]
        if len(lower) >= 2 and np.ptp(lower[:, 1]) > 0:
            lines.append(np.polyfit(lower[:, 1], lower[:, 0], 1))
    rows = []
    for (b1, a1), (b2, a2) in itertools.combinations(lines, 2):
        if abs(b1 - b2) > 1e-3:
            rows.append((a2 - a1) / (b1 - b2))
    top = min((float(p[:, 1].min()) for p in groups if len(p)), default=grid.frame_height / 2)
    if rows:
        v = float(np.median(rows))
        if v < top:
            return v
    return top - grid.cell_h


def fit_boundaries(props: Proposals, grid: CellGrid, settings: DecodeSettings,
                   camera: CameraModel | None = None) -> list[Boundary]:
    """One boundary per slot (several for "other"), fitted by RANSAC; ordered by slot.

    Mirror-symmetric: each pool's points are taken in an order by row and distance from the
    middle column, and each pool draws from its own generator, seeded alike for a slot and its
    mirror slot (ego-left and ego-right, ...), so that the mirror image of a frame's proposals
    gives the mirror image of its boundaries, not another random draw."""
    middle = (grid.frame_width - 1) / 2.0
    order = np.lexsort((np.abs(props.points_px[:, 0] - middle), props.points_px[:, 1]))
    groups = {s: order[props.slots[order] == s] for s in range(len(SLOTS))}
    horizon = None
    if camera is None:
        horizon = estimate_horizon_row([props.points_px[i] for i in groups.values()], grid)
    # "Other" boundaries lie beyond both neighbour lanes: fit each side on its own, so that
    # RANSAC never draws one curve through points of the far left and the far right.
    other = groups.pop(OTHER)
    left_side = props.points_px[other, 0] < middle
    pools = [(slot, idx, 1) for slot, idx in groups.items()]
    pools += [(OTHER, other[left_side], settings.max_other),
              (OTHER, other[~left_side], settings.max_other)]
    out = []
    for slot, idx, tries in pools:
        rng = np.random.default_rng([settings.seed, int(SLOTS[slot].startswith("next")),
                                     int(slot == OTHER)])
        for _ in range(tries):
            if len(idx) < settings.min_points:
                break
            b = _fit_one(props, idx, slot, settings, rng, camera, horizon)
            if b is None:
                break
            out.append(b[0])
            idx = idx[~b[1]]
    return out


def _fit_one(props: Proposals, idx: np.ndarray, slot: int, settings: DecodeSettings,
             rng: np.random.Generator, camera: CameraModel | None, horizon: float | None
             ) -> tuple[Boundary, np.ndarray] | None:
    """RANSAC on the proposals `idx`: (boundary, inlier mask over idx) or None."""
    pts = props.points_px[idx]
    xy = None
    if camera is not None:
        xy, ok = camera.pixels_to_ground(pts)
        ok &= np.all(np.isfinite(xy), axis=-1)
        dist = np.abs(xy[:, 0] - camera.position_m[0])
        ok &= dist < settings.max_range_m
        x = xy[:, 0]
        basis, target = np.stack([np.ones_like(x), x, x * x], -1), xy[:, 1]
        scale = np.maximum(dist, 1.0) / camera.fx  # metres per pixel across, at that distance
        prior = settings.curvature_prior_row(3)
    else:
        d = pts[:, 1] - horizon
        ok = d > 1.0
        d = np.where(ok, d, 1.0)
        basis, target = np.stack([np.ones_like(d), d, 1.0 / d], -1), pts[:, 0]
        scale = np.ones_like(d)
        prior = None  # C / d is no curvature
    if ok.sum() < settings.min_points:
        return None
    fit = ransac_fit(basis[ok], target[ok], scale[ok], settings.inlier_px, settings.iterations,
                     rng, prior)
    # evidence is counted in row bands, not points: a mirror pass reads the same rows again
    if fit is None or len(np.unique(pts[ok][fit[1], 1])) < settings.min_points:
        return None
    coeffs, inl_ok = fit
    inliers = np.zeros(len(idx), bool)
    inliers[np.flatnonzero(ok)[inl_ok]] = True
    boundary = Boundary(
        slot=slot,
        coeffs=np.asarray(coeffs, dtype=float),
        frame="ground" if camera is not None else "image",
        points_px=pts[inliers],
        score=float(props.scores[idx][inliers].mean()),
        points_xy=None if xy is None else xy[inliers],
        horizon_row=horizon,
        paint=props.paint[idx][inliers],
        scores=props.scores[idx][inliers],
    )
    return boundary, inliers


def parallel_pair(left: Boundary, right: Boundary, camera: CameraModel,
                  settings: DecodeSettings, lane_width_m: float | None = None
                  ) -> tuple[np.ndarray, np.ndarray] | None:
    """The ego pair refitted as one lane: its own c0 per side, one heading c1 and one bend c2
    (the two lines of a lane are parallel), on both sides' inlier ground points weighted to
    pixels, with the curvature prior (a Cauchy one by iteratively reweighted least squares,
    `settings.curvature_prior_shape`); points off by more than `inlier_px` (over their own
    std) are dropped and the fit repeated. A side seen only near the car (occluded, or short
    in the dark) then bends with the side seen far. Points are weighted by how surely paint is
    seen there and by the network's objectness (`settings.score_power`), and with `lane_width_m`
    and `settings.width_std_m` the pair's width is held to the lane's, so that a side inferred
    through an occluder leans on the seen one. The inlier gate reads each point's std without
    its objectness: a point the network is unsure of counts less, but is not let stray
    further. None when either side keeps fewer than 3 points."""
    blocks, targets, weights, confidence, sides = [], [], [], [], []
    for k, b in enumerate((left, right)):
        x, y = b.points_xy[:, 0], b.points_xy[:, 1]
        basis = np.zeros((len(x), 4))
        basis[:, k], basis[:, 2], basis[:, 3] = 1.0, x, x * x
        blocks.append(basis)
        targets.append(y)
        seen = np.ones(len(x)) if b.paint is None else b.paint
        px_per_m = camera.fx / np.maximum(np.abs(x - camera.position_m[0]), 1.0)
        weights.append(px_per_m * np.maximum(seen, settings.unseen_weight))
        sure = np.ones(len(x)) if b.scores is None else b.scores
        confidence.append(sure**settings.score_power)
        sides.append(np.full(len(x), k))
    basis, target = np.concatenate(blocks), np.concatenate(targets)
    w, side = np.concatenate(weights), np.concatenate(sides)
    fit_w = w * np.concatenate(confidence)  # the gate below keeps each point's own std
    prior = settings.curvature_prior_row(4)
    bend_rows = len(prior)  # the curvature prior's row comes first (none without a prior)
    prior_target = np.zeros(len(prior))
    if lane_width_m is not None and settings.width_std_m > 0:
        # c0_left - c0_right = width (parallel lines: their distance, up to cos(heading))
        scale = settings.pixel_noise_px / settings.width_std_m
        prior = np.vstack([prior, [[scale, -scale, 0.0, 0.0]]])
        prior_target = np.append(prior_target, scale * lane_width_m)
    cauchy = settings.curvature_prior_shape == "cauchy" and bend_rows > 0
    sigma_c2 = settings.curvature_prior_per_m / 2.0
    keep, bend_weight = np.ones(len(target), bool), 1.0
    for _ in range(PAIR_PASSES):
        if min(np.count_nonzero(keep & (side == k)) for k in (0, 1)) < 3:
            return None
        rows = prior.copy()
        rows[:bend_rows] *= np.sqrt(bend_weight)
        c, *_ = np.linalg.lstsq(np.vstack([basis[keep] * fit_w[keep, None], rows]),
                                np.concatenate([target[keep] * fit_w[keep], prior_target]),
                                rcond=None)
        # residual over each point's own std: an inferred point may stray further
        inliers = np.abs(basis @ c - target) * w < settings.inlier_px
        # Cauchy prior, -log p = log(1 + (c2 / sigma)^2): its IRLS weight on (c2 / sigma)^2
        weight = 1.0 / (1.0 + (c[3] / sigma_c2) ** 2) if cauchy else 1.0
        if np.array_equal(inliers, keep) and abs(weight - bend_weight) < 1e-3:
            break
        keep, bend_weight = inliers, weight
    if min(np.count_nonzero(keep & (side == k)) for k in (0, 1)) < 3:
        return None
    return np.array([c[0], c[2], c[3]]), np.array([c[1], c[2], c[3]])


def ego_estimate(boundaries: list[Boundary], camera: CameraModel | None, x_ref: float,
                 lane_width_m: float, width_tolerance_m: float,
                 settings: DecodeSettings | None = None) -> LaneEstimate:
    """The ego lane from the ego-left and ego-right ground boundaries, refitted as a parallel
    pair (`parallel_pair`; each side's own fit where that fails): offset at `x_ref` (slots are
    the camera's: a rear camera's ego-left is the vehicle's right boundary).

    Only a pair is trusted: one side and an assumed width would hide a slot mistake (the next
    lane's boundary taken for the ego one), and the pair's width is checked against the lane's.
    """
    if camera is None:
        return LaneEstimate.invalid("no camera: boundaries are in the image only", x_m=x_ref)
    by_slot = {b.slot: b for b in boundaries if b.frame == "ground"}
    left, right = by_slot.get(SLOTS.index("ego-left")), by_slot.get(SLOTS.index("ego-right"))
    if camera.rotation[0, 2] > 0:  # optical axis (-z column) points back: its left is our right
        left, right = right, left
    if left is None or right is None:
        missing = " and ".join(n for n, b in (("left", left), ("right", right)) if b is None)
        return LaneEstimate.invalid(f"ego pair not found ({missing} missing)", x_m=x_ref)
    pair = parallel_pair(left, right, camera, settings or DecodeSettings(), lane_width_m)
    c_left, c_right = pair if pair is not None else (left.coeffs, right.coeffs)
    # Where the two sides are fitted on their own (the pair failed), they are a lane only if
    # they keep its width over the stretch both are seen along, not at x_ref alone: an
    # occluded side guessed by the network can cross the other within a few metres.
    spans = [(b.points_xy[:, 0].min(), b.points_xy[:, 0].max()) for b in (left, right)]
    lo, hi = max(s[0] for s in spans), min(s[1] for s in spans)
    checks = [x_ref] if pair is not None or lo > hi else [x_ref, lo, hi]
    lane_left, lane_right = LanePoly.of(c_left), LanePoly.of(c_right)
    for x in checks:
        width = float(lane_left.y(x) - lane_right.y(x))
        if abs(width - lane_width_m) > width_tolerance_m:
            return LaneEstimate.invalid(f"ego pair {width:.2f} m apart at x = {x:.1f} m, "
                                        "not a lane", x_m=x_ref)
    y_left, y_right = float(lane_left.y(x_ref)), float(lane_right.y(x_ref))
    return LaneEstimate(
        valid=True,
        offset_m=-(y_left + y_right) / 2.0,
        x_m=x_ref,
        left=np.array(c_left, dtype=float),
        right=np.array(c_right, dtype=float),
        confidence=float(min(left.score, right.score)),
        image_points={"left": left.points_px, "right": right.points_px},
    )
