"""The scale: a robust straight line from unwrapped dial angle to value, and the ScaleModel built on it.

:func:`fit_angle_value` is RANSAC (M. A. Fischler and R. C. Bolles, CACM 24(6), 1981) with the
truncated-quadratic MSAC score (P. H. S. Torr and A. Zisserman, CVIU 78, 2000, eq. 9) and a
final least-squares refit on the consensus set, repeated until the set is stable (the
"locally optimised" step of Chum, Matas and Kittler, DAGM 2003). A gauge has few markers, so every
pair of markers is tried when there are at most ``max_trials`` pairs, which makes the result
deterministic and the consensus maximal; otherwise ``max_trials`` random pairs are drawn from ``rng``.

Residuals are measured in **angle** (radians): ``|value - (slope * angle + intercept)| / |slope|``,
so one tolerance suits every unit and range. For the same reason the refit regresses angle on value
(OCR values are exact numbers; the marker *positions* carry the noise).

Example:
    >>> angles = np.radians([135.0, 202.5, 270.0, 337.5, 405.0, 300.0])   # last one misread
    >>> values = np.array([0.0, 2.5, 5.0, 7.5, 10.0, 1.0])
    >>> fit = fit_angle_value(angles, values)
    >>> round(fit.slope * 1.5 * np.pi, 6), fit.inliers.tolist()     # 10 units over 270 degrees
    (10.0, [True, True, True, True, True, False])
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Sequence
from dataclasses import dataclass, replace

import numpy as np

from gauged.geometry.angles import unwrap, wrap_angle
from gauged.geometry.dial_frame import dial_angle, normalized_radius
from gauged.types import Ellipse, Point, ScaleMarker, ScaleModel, StageFailure

SCALE_STAGE = "scale"
DEFAULT_ANGLE_TOL = math.radians(3.0)  # marker box centres wander by a few degrees on real dials
_MIN_ANGLE_SEPARATION = 1e-3  # radians; closer pairs give no usable slope


@dataclass(frozen=True, slots=True)
class AngleValueFit:
    """``value = slope * angle + intercept`` over unwrapped dial angles (radians).

    ``inliers`` (N,) bool marks the consensus set; ``rms_value`` and ``rms_angle`` are the RMS
    residuals of the inliers in value units and radians.
    """

    slope: float
    intercept: float
    inliers: np.ndarray
    rms_value: float
    rms_angle: float


def _angle_residuals(angles: np.ndarray, values: np.ndarray, slope: float, intercept: float) -> np.ndarray:
    return np.abs(values - (slope * angles + intercept)) / abs(slope)


def _refit(angles: np.ndarray, values: np.ndarray) -> tuple[float, float] | None:
    """Least squares of angle on value over (N,) arrays; returns (slope, intercept) of value on angle."""
    spread = values - values.mean()
    denom = float(spread @ spread)
    if denom == 0.0:
        return None
    per_value = float(spread @ (angles - angles.mean())) / denom  # d angle / d value
    if per_value == 0.0 or not math.isfinite(per_value):
        return None
    slope = 1.0 / per_value
    return slope, float(values.mean() - slope * angles.mean())


def _pairs(n: int, max_trials: int, rng: np.random.Generator | None) -> np.ndarray:
    if n * (n - 1) // 2 <= max_trials:
        return np.array(list(itertools.combinations(range(n), 2)), dtype=int).reshape(-1, 2)
    rng = np.random.default_rng(0) if rng is None else rng
    first = rng.integers(0, n, max_trials)
    second = (first + rng.integers(1, n, max_trials)) % n  # never equal to first
    return np.stack([first, second], axis=1)


def fit_angle_value(
    angles: np.ndarray,
    values: np.ndarray,
    *,
    angle_tol: float = DEFAULT_ANGLE_TOL,
    min_inliers: int = 2,
    expected_sign: int | None = None,
    max_trials: int = 500,
    rng: np.random.Generator | None = None,
) -> AngleValueFit | StageFailure:
    """Robust line ``value = slope * angle + intercept`` through markers (N,) angles [rad] and (N,) values.

    ``angles`` must already be unwrapped (:func:`gauged.geometry.angles.unwrap`) so the scale is
    continuous. ``angle_tol`` is the inlier threshold in radians. ``expected_sign`` (+1 or -1), when
    given, discards hypotheses whose slope has the other sign. ``rng`` is used only when there are
    more than ``max_trials`` marker pairs (default: a fixed seed, so replays agree).

    Failures (stage ``"scale"``): ``too_few_markers`` (fewer than 2, or than ``min_inliers``),
    ``degenerate_fit`` (no pair of markers at distinct angles and values), ``wrong_slope_sign``
    (every usable pair slopes against ``expected_sign``), ``too_few_inliers``.
    """
    angles = np.asarray(angles, dtype=float).reshape(-1)
    values = np.asarray(values, dtype=float).reshape(-1)
    if angles.shape != values.shape:
        raise ValueError(f"angles {angles.shape} and values {values.shape} differ in shape")
    if not (np.all(np.isfinite(angles)) and np.all(np.isfinite(values))):
        raise ValueError("angles and values must be finite")
    needed = max(2, min_inliers)
    if len(angles) < needed:
        return StageFailure(SCALE_STAGE, "too_few_markers", f"{len(angles)} markers, need {needed}")

    pairs = _pairs(len(angles), max_trials, rng)
    d_angle = angles[pairs[:, 1]] - angles[pairs[:, 0]]
    d_value = values[pairs[:, 1]] - values[pairs[:, 0]]
    usable = (np.abs(d_angle) > _MIN_ANGLE_SEPARATION) & (d_value != 0.0)
    if not np.any(usable):
        return StageFailure(SCALE_STAGE, "degenerate_fit", "no two markers differ in both angle and value")
    slopes = d_value[usable] / d_angle[usable]
    anchors = pairs[usable, 0]
    if expected_sign is not None:
        right = np.sign(slopes) == np.sign(expected_sign)
        if not np.any(right):
            return StageFailure(SCALE_STAGE, "wrong_slope_sign", f"every marker pair slopes against {expected_sign:+d}")
        slopes, anchors = slopes[right], anchors[right]
    intercepts = values[anchors] - slopes * angles[anchors]

    # MSAC cost of every hypothesis at once: (H, N) residuals, truncated at the tolerance.
    residuals = np.abs(values[None, :] - (slopes[:, None] * angles[None, :] + intercepts[:, None]))
    residuals /= np.abs(slopes)[:, None]
    cost = np.minimum(residuals, angle_tol) ** 2
    best = int(np.argmin(cost.sum(axis=1)))
    slope, intercept = float(slopes[best]), float(intercepts[best])
    inliers = residuals[best] < angle_tol

    for _ in range(10):  # local optimisation: refit on the consensus set until it stops changing
        refit = _refit(angles[inliers], values[inliers]) if inliers.sum() >= 2 else None
        if refit is None or (expected_sign is not None and np.sign(refit[0]) != np.sign(expected_sign)):
            break
        new_inliers = _angle_residuals(angles, values, *refit) < angle_tol
        if new_inliers.sum() < inliers.sum():
            break
        slope, intercept = refit
        if np.array_equal(new_inliers, inliers):
            break
        inliers = new_inliers

    if inliers.sum() < needed:
        return StageFailure(SCALE_STAGE, "too_few_inliers", f"{int(inliers.sum())} inliers, need {needed}")
    value_residuals = values[inliers] - (slope * angles[inliers] + intercept)
    rms_value = float(np.sqrt(np.mean(value_residuals**2)))
    return AngleValueFit(slope, intercept, inliers, rms_value, rms_value / abs(slope))


def marker_centres(markers: Sequence[ScaleMarker]) -> np.ndarray:
    """Centres (N, 2) px of the markers' boxes."""
    boxes = np.array([m.box for m in markers], dtype=float).reshape(-1, 4)
    return np.stack([(boxes[:, 0] + boxes[:, 2]) / 2.0, (boxes[:, 1] + boxes[:, 3]) / 2.0], axis=1)


RING_GAP = 0.12  # normalised-radius gap that separates the numbers of two scales


def number_rings(ellipse: Ellipse, markers: Sequence[ScaleMarker], min_gap: float = RING_GAP,
                 min_ring: int = 2) -> list[list[ScaleMarker]]:
    """The markers grouped into rings of scale numbers, outermost first.

    The numbers of one scale sit at about the same radius in the dial frame of ``ellipse``
    (:func:`gauged.geometry.dial_frame.normalized_radius`); a dual-scale dial prints its second scale's
    numbers on another radius. The markers are split at the widest gap between sorted radii when it
    exceeds ``min_gap`` and leaves at least ``min_ring`` markers on each side; otherwise they form one
    ring. (Splitting at the scale ellipse itself fails when both rings print inside it.)
    """
    markers = list(markers)
    if not markers:
        return []
    radius = normalized_radius(ellipse, marker_centres(markers))
    order = np.argsort(-radius, kind="stable")
    gaps = -np.diff(radius[order])
    candidates = [k for k in range(len(gaps)) if min_ring <= k + 1 <= len(markers) - min_ring]
    if candidates:
        k = max(candidates, key=lambda i: gaps[i])
        if gaps[k] > min_gap:
            return [[markers[i] for i in sorted(order[:k + 1])], [markers[i] for i in sorted(order[k + 1:])]]
    return [markers]


def fit_scale_model(
    ellipse: Ellipse,
    markers: Sequence[ScaleMarker],
    start_angle: float,
    end_angle: float,
    *,
    unit: str | None = None,
    centre: Point | np.ndarray | None = None,
    angle_tol: float = DEFAULT_ANGLE_TOL,
    min_inliers: int = 2,
    expected_sign: int | None = None,
    rng: np.random.Generator | None = None,
) -> ScaleModel | StageFailure:
    """ScaleModel of one scale from its OCR markers and the start/end notch dial angles (radians).

    A marker's ``angle`` is used when set (a dial angle, :func:`gauged.geometry.dial_frame.dial_angle`),
    otherwise computed from its box centre with the same ``centre`` convention. The zero angle is
    :func:`gauged.geometry.angles.wrap_angle` of the notches; ``min_value``/``max_value`` are the
    fitted values at the two notches, in ascending order. The returned markers carry their dial
    angle and inlier flag. Failures are those of :func:`fit_angle_value`.
    """
    markers = list(markers)
    zero = wrap_angle(start_angle, end_angle)
    if markers:
        missing = [i for i, m in enumerate(markers) if m.angle is None]
        if missing:
            computed = dial_angle(ellipse, marker_centres([markers[i] for i in missing]), centre)
            for i, angle in zip(missing, computed, strict=True):
                markers[i] = replace(markers[i], angle=float(angle))
    angles = np.array([unwrap(m.angle, zero) for m in markers], dtype=float)
    values = np.array([m.value for m in markers], dtype=float)
    fit = fit_angle_value(
        angles, values, angle_tol=angle_tol, min_inliers=min_inliers, expected_sign=expected_sign, rng=rng
    )
    if not fit:
        return fit
    # Rounded off float noise: a scale from 0 is not shown as -1.8e-15..10.
    at_notches = sorted(round(fit.slope * unwrap(a, zero) + fit.intercept, 12) + 0.0 for a in (start_angle, end_angle))
    return ScaleModel(
        ellipse=ellipse,
        slope=fit.slope,
        intercept=fit.intercept,
        zero_angle=zero,
        min_value=float(at_notches[0]),
        max_value=float(at_notches[1]),
        unit=unit,
        inliers=int(fit.inliers.sum()),
        rms_value=fit.rms_value,
        markers=tuple(replace(m, inlier=bool(flag)) for m, flag in zip(markers, fit.inliers, strict=True)),
    )
