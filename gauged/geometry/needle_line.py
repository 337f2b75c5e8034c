"""The needle as a line: total-least-squares fit through its pixels, and where it meets the scale ellipse.

- :func:`fit_needle_line` -- orthogonal (total) least squares: the line through the (weighted)
  centroid along the principal axis of the pixel scatter, i.e. the first right singular vector of the
  centred coordinates (Pearson 1901; Golub & Van Loan, *Matrix Computations*, 4th ed., sec. 6.3).
  The smallest singular value gives the orthogonal residual. The sign of the direction is chosen so
  it points from the tail (pivot side) to the tip, the tip being the end of the pixel extent farther
  from the given pivot.
- :func:`intersect_line_ellipse` -- substitutes the line into the ellipse after the affine map of
  :mod:`gauged.geometry.dial_frame` (which turns it into the unit circle and keeps the line
  parameter), solving ``|q + s e|^2 = 1`` for ``s``; :func:`needle_dial_angle` turns that point into
  the dial angle the scale is read at.

Example:
    >>> from gauged.types import Ellipse
    >>> pixels = np.stack([np.linspace(100.0, 160.0, 61), np.full(61, 100.0)], axis=1)
    >>> pixels[::2, 1] += 1.0   # a needle two pixels thick
    >>> line = fit_needle_line(pixels, pivot=(100.0, 100.0))
    >>> [round(v, 3) for v in line.direction], [round(v, 3) for v in line.tip]
    ([1.0, 0.0], [160.0, 100.508])
    >>> hit = intersect_line_ellipse(Ellipse(100.0, 100.0, 80.0, 80.0, 0.0), line.point, line.direction)
    >>> [round(float(v), 3) for v in hit]
    [179.998, 100.508]
"""

from __future__ import annotations

import math

import numpy as np

from gauged.geometry.dial_frame import as_points, dial_angle, rectifying_matrix
from gauged.types import Ellipse, NeedleLine, Point, StageFailure

NEEDLE_STAGE = "needle"


def fit_needle_line(
    pixels: np.ndarray,
    pivot: Point | np.ndarray,
    *,
    weights: np.ndarray | None = None,
    min_pixels: int = 10,
    max_axis_ratio: float = 0.5,
) -> NeedleLine | StageFailure:
    """Total-least-squares line through needle pixels (N, 2) px, oriented from tail to tip.

    ``pivot`` (2,) px is the needle's rotation centre (or the dial centre) and decides which end is
    the tip: the end of the pixel extent along the line that is farther from it. ``weights`` (N,)
    >= 0 (e.g. mask probabilities) weight the centroid and scatter. ``min_pixels`` is the minimum
    support; ``max_axis_ratio`` the largest accepted ratio of the minor to the major singular value
    (1 for a round blob, ~width/length for a needle).

    Returns :class:`NeedleLine` with ``point`` the centroid, ``direction`` a unit vector,
    ``tip`` the centroid-line point at the farthest pixel projection along ``direction`` (the pixel
    projected onto the line, so it lies on the fitted line), ``rms_px`` the weighted orthogonal RMS
    residual and ``support`` the number of pixels with positive weight. Failures (stage
    ``"needle"``): ``too_few_pixels``, ``degenerate_line`` (no dominant direction).
    """
    pixels = as_points(pixels, "pixels")
    pivot = np.asarray(pivot, dtype=float).reshape(2)
    if weights is None:
        w = np.ones(len(pixels))
    else:
        w = np.asarray(weights, dtype=float).reshape(-1)
        if w.shape != (len(pixels),) or np.any(w < 0.0) or not np.all(np.isfinite(w)):
            raise ValueError("weights must be finite, non-negative and have shape (N,)")
    keep = w > 0.0
    pixels, w = pixels[keep], w[keep]
    if len(pixels) < max(min_pixels, 2):
        return StageFailure(NEEDLE_STAGE, "too_few_pixels", f"{len(pixels)} pixels, need {max(min_pixels, 2)}")
    total = float(w.sum())
    centroid = (w[:, None] * pixels).sum(axis=0) / total
    centred = (pixels - centroid) * np.sqrt(w / total)[:, None]
    _, singular, vt = np.linalg.svd(centred, full_matrices=False)
    if singular[0] == 0.0 or singular[1] > max_axis_ratio * singular[0]:
        ratio = singular[1] / singular[0] if singular[0] > 0.0 else 1.0
        return StageFailure(NEEDLE_STAGE, "degenerate_line", f"minor/major axis ratio {ratio:.2f} > {max_axis_ratio}")
    direction = vt[0]
    along = (pixels - centroid) @ direction
    ends = centroid + np.outer([along.min(), along.max()], direction)
    if np.linalg.norm(ends[0] - pivot) > np.linalg.norm(ends[1] - pivot):
        direction = -direction
        along = -along
    tip = centroid + along.max() * direction
    return NeedleLine(
        point=(float(centroid[0]), float(centroid[1])),
        direction=(float(direction[0]), float(direction[1])),
        tip=(float(tip[0]), float(tip[1])),
        rms_px=float(singular[1]),
        support=int(len(pixels)),
    )


def intersect_line_ellipse(
    ellipse: Ellipse, point: Point | np.ndarray, direction: Point | np.ndarray
) -> np.ndarray | StageFailure:
    """Where the line ``point + s * direction`` (s >= 0) leaves ``ellipse``: a (2,) float64 point in px.

    Of the (up to) two intersections the one farthest along ``direction`` is returned, which for a
    point inside the ellipse is the one on the tip side. Failures (stage ``"needle"``):
    ``no_intersection`` when the line misses the ellipse, ``intersection_behind`` when it meets it
    only at ``s < 0`` (the point is outside and the direction points away).
    """
    point = np.asarray(point, dtype=float).reshape(2)
    direction = np.asarray(direction, dtype=float).reshape(2)
    if not np.any(direction):
        raise ValueError("direction must be non-zero")
    k = rectifying_matrix(ellipse)
    q = k @ (point - np.array(ellipse.center))
    e = k @ direction
    # |q + s e|^2 = 1  <=>  (e.e) s^2 + 2 (q.e) s + (q.q - 1) = 0
    aa, bb, cc = e @ e, q @ e, q @ q - 1.0
    disc = bb * bb - aa * cc
    if disc < 0.0:
        off = math.sqrt(max(q @ q - bb * bb / aa, 0.0))  # line-centre distance in radii of the dial
        return StageFailure(NEEDLE_STAGE, "no_intersection", f"the line passes {off:.3g} radii from the centre")
    root = math.sqrt(disc)
    # The larger root, written to avoid cancellation when bb and root are close (Numerical Recipes 5.6).
    s_far = (-bb + root) / aa if bb <= 0.0 else -cc / (bb + root)
    if s_far < 0.0:
        return StageFailure(NEEDLE_STAGE, "intersection_behind", "the ellipse lies behind the point")
    return point + s_far * direction


def needle_dial_angle(
    ellipse: Ellipse, needle: NeedleLine, centre: Point | np.ndarray | None = None
) -> float | StageFailure:
    """Dial angle (radians, :func:`gauged.geometry.dial_frame.dial_angle`) where the needle meets the scale.

    Intersects the needle line with ``ellipse`` on the tip side (from the needle's centroid towards
    its tip) and takes the dial angle of that point, with the same optional ``centre`` the scale was
    calibrated with. Failures are those of :func:`intersect_line_ellipse`.
    """
    hit = intersect_line_ellipse(ellipse, needle.point, needle.direction)
    if isinstance(hit, StageFailure):
        return hit
    return float(dial_angle(ellipse, hit[None, :], centre)[0])
