"""Robust search for the scale ring among notch points: RANSAC ellipses with an adaptive trial count, a\nsecond concentric ring of a dual-scale dial, and circles about a known centre."""

from __future__ import annotations

import numpy as np

from gauged.geometry.conic import STAGE, conic_to_ellipse
from gauged.geometry.dial_frame import normalized_radius
from gauged.geometry.ellipse_distance import orthogonal_distance
from gauged.geometry.ellipse_fit import fit_circle, fit_ellipse, fit_ellipses_direct
from gauged.types import Ellipse, StageFailure

CIRCLE_UNLESS = 1.5  # a pivot-centred circle is kept unless its notch RMS exceeds the ellipse's this much (+0.5 px)


MIN_TRIALS = 40  # RANSAC hypotheses tried before the adaptive count may stop the search


def _robust_fit(points: np.ndarray, tol_px: float, trials: int = 300) -> tuple[Ellipse, np.ndarray] | StageFailure:
    """RANSAC over 5-notch ellipse hypotheses (3-notch circles when fewer), then a refit on the inliers.

    The number of hypotheses adapts to the best inlier share so far (99% chance of one all-inlier
    sample, at least :data:`MIN_TRIALS`, at most ``trials``): a clean single ring stops early, a
    dual-scale dial whose ring holds half the notches gets the hundred-odd samples it needs.

    False notch peaks (a screw head, a printed logo) pull a plain least-squares conic far off the
    ring, so the consensus set is found first. The sampling generator has a fixed seed: the same
    notches always give the same ellipse, so replays reproduce readings bit for bit.
    """
    count = len(points)
    sample = 5 if count >= 6 else 3
    if count <= sample:
        ellipse = fit_ellipse(points, shape="auto")
        if isinstance(ellipse, StageFailure):
            return StageFailure(STAGE, "degenerate_conic", ellipse.detail)
        return ellipse, np.ones(count, bool)
    rng = np.random.default_rng(0)
    best_keep, best_cost, needed = None, np.inf, trials
    trial = 0
    while trial < (stop := min(trials, max(MIN_TRIALS, needed))):
        # The samples up to the current stopping count are drawn and scored in one batch, then taken
        # in order: the same search, sample for sample, as one hypothesis at a time.
        subsets = [rng.choice(count, sample, replace=False) for _ in range(trial, stop)]
        dists, usable = _hypothesis_distances(points, points[np.array(subsets)])
        for dist, ok in zip(dists, usable, strict=True):
            if trial >= max(MIN_TRIALS, needed):
                break
            trial += 1
            if not ok:
                continue
            cost = float(np.minimum(dist, tol_px).sum())  # MSAC (Torr & Zisserman 2000)
            if cost < best_cost:
                best_cost, best_keep = cost, dist <= tol_px
                needed = _trials_needed(best_keep.mean(), sample, trials)
    if best_keep is None or best_keep.sum() < 3:
        return StageFailure(STAGE, "degenerate_conic", "no ellipse hypothesis from the notches")
    keep = best_keep
    for _ in range(3):  # refit on the consensus set until it is stable
        ellipse = fit_ellipse(points[keep], shape="auto")
        if isinstance(ellipse, StageFailure):
            return StageFailure(STAGE, "degenerate_conic", ellipse.detail)
        new_keep = np.abs(orthogonal_distance(ellipse, points)) <= tol_px
        if new_keep.sum() < 3 or np.array_equal(new_keep, keep):
            break
        keep = new_keep
    return ellipse, keep


def _hypothesis_distances(points: np.ndarray, subsets: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Distances (K, N) px of ``points`` from the ellipse (5-point ``subsets``) or circle (3 points)
    through each of the K subsets (K, n, 2), and which hypotheses are usable: a real ellipse not
    flatter than 1:5. The distance is radial in the hypothesis's dial frame: cheap, and close to the
    orthogonal one near the ring."""
    if subsets.shape[1] == 5:
        hypotheses = fit_ellipses_direct(subsets)
        usable = hypotheses.ok & (hypotheses.b >= 0.2 * hypotheses.a)
        radius = np.where(usable[:, None], hypotheses.normalized_radius(points), 1.0)
        return np.abs(radius - 1.0) * np.sqrt(hypotheses.a * hypotheses.b)[:, None], usable
    circles = [fit_circle(subset) for subset in subsets]  # 4-5 notches only: a handful of samples
    usable = np.array([not isinstance(c, StageFailure) for c in circles])
    dists = np.array([np.abs(normalized_radius(c, points) - 1.0) * c.a if ok else np.zeros(len(points))
                      for c, ok in zip(circles, usable, strict=True)])
    return dists, usable


def _trials_needed(inlier_share: float, sample: int, cap: int) -> int:
    """RANSAC samples for a 99% chance that one is all inliers (Fischler & Bolles 1981)."""
    p_good = inlier_share ** sample
    if p_good >= 1.0:
        return 0
    if p_good <= 0.0:
        return cap
    return min(cap, int(np.ceil(np.log(0.01) / np.log1p(-p_good))))


CONCENTRIC = 0.06  # centres of two scale rings of one dial lie within this fraction of the outer radius


def _scale_ring(points: np.ndarray, ellipse: Ellipse, inliers: np.ndarray, ends: np.ndarray, tol_px: float,
                min_notches: int) -> tuple[Ellipse, np.ndarray, int]:
    """The ring of the primary scale on a dial with two concentric scales (bar outside, psi inside).

    The major-notch map marks the notches of both scales, so the consensus of :func:`_robust_fit` may
    hold only one ring. The other ring is looked for among the remaining notches, as the first ring
    scaled about its centre (:func:`_concentric_ring`) or as a free ellipse; and since the first
    consensus may be the worse-fitted ring (a short, noisy inner arc), also the other way round.
    Of the pairs of concentric, separate rings the one explaining most notches wins, and the scale
    is its ring holding the start/end notches (``ends`` marks those points), else the outer one.
    Without such a pair the first fit is returned unchanged and the caller judges it. The third
    value is how many notches the ring(s) explain.
    """
    best: tuple[Ellipse, np.ndarray, int] = (ellipse, inliers, int(inliers.sum()))
    for first, first_inliers, second in _ring_pairs(points, ellipse, inliers, tol_px, min_notches):
        other, other_inliers = second
        outer = max(first.a, other.a)
        concentric = np.hypot(first.cx - other.cx, first.cy - other.cy) <= CONCENTRIC * outer
        separate = abs(first.a - other.a) > 2 * tol_px
        explained = int((first_inliers | other_inliers).sum())
        if not (concentric and separate and other_inliers.sum() >= min_notches and explained > best[2]):
            continue
        rings = [(first, first_inliers), (other, other_inliers)]
        rings.sort(key=lambda ring: (int((ring[1] & ends).sum()), ring[0].a), reverse=True)
        best = rings[0][0], rings[0][1], explained
    return best


def _ring_pairs(points: np.ndarray, ellipse: Ellipse, inliers: np.ndarray, tol_px: float, min_notches: int):
    """Candidate (first ring, its inliers, (second ring, its inliers)) pairs for :func:`_scale_ring`."""
    def second_ring(ring: Ellipse, taken: np.ndarray) -> list[tuple[Ellipse, np.ndarray]]:
        rest = np.flatnonzero(~taken)
        if len(rest) < min_notches:
            return []
        found = []
        for fit in (_concentric_ring(points[rest], ring, tol_px, min_notches), _robust_fit(points[rest], tol_px)):
            if fit is not None and not isinstance(fit, StageFailure):
                mask = np.zeros(len(points), bool)
                mask[rest[fit[1]]] = True
                found.append((fit[0], mask))
        return found

    for other, other_inliers in second_ring(ellipse, inliers):
        yield ellipse, inliers, (other, other_inliers)
        # the second ring may be the better-fitted one: find the first again as its scaled copy
        for again in second_ring(other, other_inliers)[:1]:
            yield other, other_inliers, again


def _concentric_ring(points: np.ndarray, ellipse: Ellipse, tol_px: float,
                     min_notches: int) -> tuple[Ellipse, np.ndarray] | None:
    """A second scale ring among ``points``: the first ring scaled about its centre, or None.

    The two rings of a dual-scale dial are concentric circles on one plane, so in the image the
    second is the first ellipse scaled about (nearly) the same centre. Fitting it as a free ellipse
    fails when its notches cover a short arc (a 0-50 inner scale on a quarter of the dial), so the
    notches are grouped by their normalised radius in the first ring's frame: the largest group
    within ``tol_px`` of one radius is the ring. It is refitted freely only when that refit stays
    concentric and of the same shape (perspective shifts the inner ring's image slightly).
    """
    scale = float(np.sqrt(ellipse.a * ellipse.b))
    rho = normalized_radius(ellipse, points)
    members = np.abs(rho[:, None] - rho[None, :]) * scale <= tol_px
    counts = members.sum(axis=1)
    k = int(np.argmax(counts))
    if counts[k] < min_notches:
        return None
    ratio = float(np.median(rho[members[k]]))
    if abs(ratio - 1.0) * scale <= 2 * tol_px:
        return None  # the same ring, not a second one
    ring = Ellipse(ellipse.cx, ellipse.cy, ellipse.a * ratio, ellipse.b * ratio, ellipse.theta)
    keep = np.abs(normalized_radius(ring, points) - 1.0) * scale * ratio <= tol_px
    if keep.sum() >= 6:
        refit = fit_ellipse(points[keep], shape="auto")
        if (not isinstance(refit, StageFailure)
                and np.hypot(refit.cx - ring.cx, refit.cy - ring.cy) <= CONCENTRIC * max(ellipse.a, ring.a)
                and abs(refit.b / refit.a - ring.b / ring.a) <= 0.05 and abs(refit.a / ring.a - 1.0) <= 0.1):
            ring = refit
            keep = np.abs(orthogonal_distance(ring, points)) <= tol_px
    return ring, keep


def _coverage(points: np.ndarray, centre: np.ndarray) -> float:
    """The angle (radians) the points cover about ``centre``: a full turn less the largest gap."""
    if len(points) < 2:
        return 0.0
    angles = np.sort(np.arctan2(points[:, 1] - centre[1], points[:, 0] - centre[0]))
    gaps = np.diff(np.concatenate([angles, angles[:1] + 2 * np.pi]))
    return float(2 * np.pi - gaps.max())


def _centred_fit(points: np.ndarray, centre: np.ndarray, tol_px: float) -> tuple[Ellipse, np.ndarray] | None:
    """The ring through ``points`` centred on ``centre`` (the needle pivot), with its inliers.

    A centred conic ``A x^2 + B xy + C y^2 = 1`` is linear in its three coefficients; it is refitted
    on the points within ``tol_px`` until stable. A short arc barely determines the shape, so the
    circle about the centre is taken unless its RMS is :data:`CIRCLE_UNLESS` times the ellipse's
    (plus half a pixel), and always when the conic is no ellipse or is flatter than 3:1. None when
    fewer than four points stay on the ring.
    """
    rel = np.asarray(points, float) - centre
    keep = np.ones(len(rel), bool)
    ellipse = None
    for _ in range(5):
        if keep.sum() < 4:
            return None
        x, y = rel[keep].T
        coef, *_ = np.linalg.lstsq(np.stack([x * x, x * y, y * y], axis=1), np.ones(len(x)), rcond=None)
        conic = conic_to_ellipse(np.array([coef[0], coef[1], coef[2], 0.0, 0.0, -1.0]))
        if isinstance(conic, StageFailure) or conic.b < 0.35 * conic.a:
            radius = float(np.median(np.hypot(x, y)))
            ellipse = Ellipse(float(centre[0]), float(centre[1]), radius, radius, 0.0)
        else:
            ellipse = Ellipse(float(centre[0]), float(centre[1]), conic.a, conic.b, conic.theta)
        new_keep = np.abs(orthogonal_distance(ellipse, points)) <= tol_px
        if np.array_equal(new_keep, keep):
            break
        keep = new_keep
    if ellipse is None or keep.sum() < 4:
        return None
    # A short arc barely tells an ellipse from a circle: the circle wins unless clearly worse.
    radius = float(np.median(np.hypot(*rel[keep].T)))
    circle = Ellipse(float(centre[0]), float(centre[1]), radius, radius, 0.0)
    rms = [float(np.sqrt(np.mean(orthogonal_distance(e, points[keep]) ** 2))) for e in (circle, ellipse)]
    if rms[0] <= CIRCLE_UNLESS * rms[1] + 0.5:
        ellipse = circle
        keep = np.abs(orthogonal_distance(circle, points)) <= tol_px
    return (ellipse, keep) if keep.sum() >= 4 else None
