"""Fitting an ellipse (or a circle) to points: algebraic fits, optionally refined geometrically.

- :func:`fit_ellipse_direct` -- R. Halir and J. Flusser, "Numerically stable direct least squares
  fitting of ellipses", WSCG 1998: the ellipse-specific direct fit of Fitzgibbon, Pilu and Fisher
  (PAMI 1999) minimising the algebraic distance subject to ``4AC - B^2 = 1``, with the scatter matrix
  split into quadratic and linear blocks (their eqs. 11-15) so the generalised eigenproblem becomes a
  well-posed 3x3 ordinary one. Points are first centred on their mean and scaled to unit RMS radius
  (Hartley-style normalisation) so the monomials ``x^2 .. 1`` have comparable magnitudes.
  :func:`fit_ellipses_direct` is the same fit of many point sets at once (RANSAC samples).
- :func:`fit_circle` -- N. Chernov's SVD form of V. Pratt, "Direct least-squares fitting of algebraic
  surfaces", SIGGRAPH 1987 (``method="pratt"``, default: nearly unbiased on short arcs), or
  I. Kasa, "A circle fitting procedure and its error analysis", IEEE TIM 1976 (``method="kasa"``,
  ordinary least squares on ``x^2 + y^2 + D x + E y + F``; biased small on short arcs).
- :func:`fit_ellipse` -- what the reader calls: one of the above by ``shape`` (``"auto"`` chooses by
  Kanatani's geometric AIC), optionally followed by the geometric refinement of
  :mod:`gauged.geometry.ellipse_refine`.

Example:
    >>> from gauged.types import Ellipse
    >>> truth = Ellipse(320.0, 240.0, 150.0, 100.0, 0.3)
    >>> fit = fit_ellipse(truth.point_at(np.linspace(0.0, 4.7, 12)))
    >>> [round(v, 6) for v in (fit.cx, fit.cy, fit.a, fit.b, fit.theta)]
    [320.0, 240.0, 150.0, 100.0, 0.3]
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numpy as np

from gauged.geometry.conic import STAGE, conic_forms, conic_to_ellipse, normalized_ellipse
from gauged.geometry.dial_frame import as_points
from gauged.geometry.ellipse_distance import orthogonal_distance
from gauged.geometry.ellipse_refine import refine_ellipse
from gauged.types import Ellipse, StageFailure

# Below this ratio of the 5th to the 1st singular value of the design matrix, fewer than five
# points are independent (duplicates, or all on one line) and the conic is not determined.
_RANK_TOLERANCE = 1e-9

Shape = Literal["ellipse", "circle", "auto"]


def _normalize(points: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Centre point sets (..., N, 2) on their means and scale each to unit RMS radius; returns
    (normalised, mean (..., 2), scale (...))."""
    mean = points.mean(axis=-2)
    centred = points - mean[..., None, :]
    scale = np.sqrt(np.mean(np.sum(centred * centred, axis=-1), axis=-1))
    scale = np.where(scale == 0.0, 1.0, scale)  # all points identical: the rank test reports it
    return centred / scale[..., None, None], mean, scale


def _denormalize(ellipse: Ellipse, mean: np.ndarray, scale: np.ndarray) -> Ellipse:
    return normalized_ellipse(
        ellipse.cx * scale + mean[0], ellipse.cy * scale + mean[1], ellipse.a * scale, ellipse.b * scale, ellipse.theta
    )


def _direct_conics(norm: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Halir-Flusser on K normalised point sets (K, N, 2), N >= 5, at once.

    Returns the conics (K, 6) in the normalised frame and a status (K,) int: 0 fitted, 1 fewer than 5
    independent points, 2 no eigenvector satisfies the ellipse constraint (conics of status != 0 are
    meaningless).
    """
    x, y = norm[..., 0], norm[..., 1]
    d1 = np.stack([x * x, x * y, y * y], axis=-1)  # quadratic part of the design matrix
    d2 = np.stack([x, y, np.ones_like(x)], axis=-1)  # linear part
    singular = np.linalg.svd(np.concatenate([d1, d2], axis=-1), compute_uv=False)
    status = np.where(singular[:, 4] <= _RANK_TOLERANCE * singular[:, 0], 1, 0)
    d1t = np.swapaxes(d1, 1, 2)
    s1, s2, s3 = d1t @ d1, d1t @ d2, np.swapaxes(d2, 1, 2) @ d2
    s3[status == 1] = np.eye(3)  # collinear points: s3 is singular, and the fit is refused anyway
    t = -np.linalg.solve(s3, np.swapaxes(s2, 1, 2))  # eq. 14: the linear coefficients from the quadratic
    m = s1 + s2 @ t  # reduced scatter matrix, eq. 15
    m = np.stack([m[:, 2] / 2.0, -m[:, 1], m[:, 0] / 2.0], axis=1)  # premultiply by inv(C1)
    _, vectors = np.linalg.eig(m)
    vectors = np.real(vectors)
    # Exactly one eigenvector satisfies the ellipse constraint 4 a0 a2 - a1^2 > 0 (their sec. 3);
    # taking the most elliptic one is the same thing and is robust to rounding on exact data.
    cond = (4.0 * vectors[:, 0] * vectors[:, 2] - vectors[:, 1] ** 2) / np.sum(vectors * vectors, axis=1)
    best = np.argmax(cond, axis=1)
    rows = np.arange(len(norm))
    status = np.where((status == 0) & (cond[rows, best] <= 0.0), 2, status)
    quadratic = vectors[rows, :, best]
    return np.concatenate([quadratic, (t @ quadratic[:, :, None])[:, :, 0]], axis=1), status


def fit_ellipse_direct(points: np.ndarray) -> Ellipse | StageFailure:
    """Halir-Flusser direct least-squares ellipse through points (N, 2) px, N >= 5.

    Always returns an ellipse when the points determine one (the constraint excludes hyperbolas);
    ``StageFailure("ellipse", "too_few_points")`` below 5 points and
    ``StageFailure("ellipse", "degenerate_conic")`` when fewer than 5 points are independent
    (duplicates, collinear points) or the solution is not a real ellipse.
    """
    points = as_points(points)
    if len(points) < 5:
        return StageFailure(STAGE, "too_few_points", f"{len(points)} points, an ellipse needs 5")
    norm, mean, scale = _normalize(points)
    conics, status = _direct_conics(norm[None])
    if status[0] == 1:
        return StageFailure(STAGE, "degenerate_conic", "fewer than 5 independent points (duplicates or a line)")
    if status[0] == 2:
        return StageFailure(STAGE, "degenerate_conic", "no eigenvector satisfies the ellipse constraint")
    fitted = conic_to_ellipse(conics[0])
    if not fitted:
        return fitted
    return _denormalize(fitted, mean, scale)


@dataclass(frozen=True, slots=True)
class EllipseHypotheses:
    """K ellipses in matrix form, for scoring many RANSAC samples at once: a point ``p`` (px) lies at
    normalised radius ``sqrt((p - centre)^T form (p - centre))`` (1 on the ellipse); ``a``, ``b``
    are the semi-axes (px, ``a >= b``) and ``ok`` marks the samples that gave a real ellipse (the
    other rows are meaningless)."""

    centre: np.ndarray  # (K, 2)
    form: np.ndarray  # (K, 2, 2)
    a: np.ndarray  # (K,)
    b: np.ndarray  # (K,)
    ok: np.ndarray  # (K,) bool

    def normalized_radius(self, points: np.ndarray) -> np.ndarray:
        """(K, N) radius of each of points (N, 2) in each ellipse's affine dial frame."""
        d = np.asarray(points, float)[None] - self.centre[:, None]
        with np.errstate(invalid="ignore"):
            return np.sqrt(np.einsum("kni,kij,knj->kn", d, self.form, d))


def fit_ellipses_direct(samples: np.ndarray) -> EllipseHypotheses:
    """:func:`fit_ellipse_direct` of K point sets (K, N, 2) px, N >= 5, in one vectorised pass.

    A sample is ``ok`` exactly when :func:`fit_ellipse_direct` would return an ellipse for it (the
    same rank, constraint and :func:`gauged.geometry.conic.conic_to_ellipse` tests, up to rounding).
    """
    norm, mean, scale = _normalize(np.asarray(samples, float))
    conics, status = _direct_conics(norm)
    centre, form, a, b, ok = conic_forms(conics)
    return EllipseHypotheses(centre * scale[:, None] + mean, form / (scale * scale)[:, None, None],
                             a * scale, b * scale, ok & (status == 0))


def fit_circle(points: np.ndarray, method: Literal["pratt", "kasa"] = "pratt") -> Ellipse | StageFailure:
    """Algebraic circle through points (N, 2) px, N >= 3, as an Ellipse with ``a == b`` and ``theta = 0``.

    ``StageFailure("ellipse", "too_few_points")`` below 3 points, ``"degenerate_conic"`` for collinear
    or coincident points (the circle's radius is unbounded).
    """
    points = as_points(points)
    if len(points) < 3:
        return StageFailure(STAGE, "too_few_points", f"{len(points)} points, a circle needs 3")
    norm, mean, scale = _normalize(points)
    x, y = norm[:, 0], norm[:, 1]
    design = np.stack([x * x + y * y, x, y, np.ones_like(x)], axis=1)
    if method == "kasa":
        # x^2 + y^2 + D x + E y + F = 0 by ordinary least squares.
        solution, _, rank, _ = np.linalg.lstsq(design[:, 1:], -design[:, 0], rcond=None)
        coef = np.concatenate([[1.0], solution]) if rank == 3 else np.zeros(4)
    elif method == "pratt":
        _, sv, vt = np.linalg.svd(design, full_matrices=True)  # vt is 4x4 even for 3 points
        if len(sv) < 4 or sv[3] < 1e-12 * sv[0]:
            coef = vt[3]  # null vector: the points fit a circle (or a line) exactly
        else:
            # Pratt's constraint B^2 + C^2 - 4 A D = 1 as a generalised eigenproblem (Chernov 2010, sec. 5.5).
            w = vt.T @ np.diag(sv) @ vt
            b_inv = np.array([[0, 0, 0, -0.5], [0, 1, 0, 0], [0, 0, 1, 0], [-0.5, 0, 0, 0]])
            eigval, eigvec = np.linalg.eig(w @ b_inv @ w)
            order = np.argsort(np.real(eigval))
            coef = vt.T @ np.diag(1.0 / sv) @ vt @ np.real(eigvec[:, order[1]])
    else:
        raise ValueError(f"unknown circle fit method {method!r}")
    a_, d_, e_, f_ = coef
    if abs(a_) < 1e-12 * max(np.abs(coef).max(), 1e-300):
        return StageFailure(STAGE, "degenerate_conic", "collinear points: the circle has no finite radius")
    radius_sq = (d_ * d_ + e_ * e_ - 4.0 * a_ * f_) / (4.0 * a_ * a_)
    if not np.isfinite(radius_sq) or radius_sq <= 0.0:
        return StageFailure(STAGE, "degenerate_conic", "imaginary circle")
    circle = Ellipse(-d_ / (2.0 * a_), -e_ / (2.0 * a_), float(np.sqrt(radius_sq)), float(np.sqrt(radius_sq)), 0.0)
    return _denormalize(circle, mean, scale)


def select_circle_or_ellipse(
    points: np.ndarray, circle: Ellipse, ellipse: Ellipse, noise_px: float | None = None
) -> Ellipse:
    """Pick the circle or the ellipse fitted to points (N, 2) px by Kanatani's geometric AIC.

    K. Kanatani, "Geometric information criterion for model selection", IJCV 26 (1998), eq. 29:
    ``G-AIC = J + 2 (d N + p) sigma^2`` with ``J`` the sum of squared orthogonal residuals, ``d = 1``
    for curves and ``p`` the number of parameters (3 for a circle, 5 for an ellipse). The circle wins
    when ``J_circle - J_ellipse <= 4 sigma^2``. ``sigma`` is ``noise_px`` when known, otherwise
    estimated as ``sqrt(J_ellipse / (N - 5))``; with N <= 5 and no ``noise_px`` the ellipse is kept.
    A frontal dial read as a circle halves the angle error of a free ellipse (see docs/geometry.md).
    """
    points = as_points(points)
    j_ellipse = float(np.sum(orthogonal_distance(ellipse, points) ** 2))
    j_circle = float(np.sum(orthogonal_distance(circle, points) ** 2))
    if noise_px is not None:
        sigma_sq = float(noise_px) ** 2
    elif len(points) > 5:
        sigma_sq = j_ellipse / (len(points) - 5)
    else:
        return ellipse
    return circle if j_circle - j_ellipse <= 4.0 * sigma_sq else ellipse


def fit_ellipse(
    points: np.ndarray,
    *,
    shape: Shape = "ellipse",
    refine: bool = False,
    noise_px: float | None = None,
    max_iterations: int = 50,
) -> Ellipse | StageFailure:
    """Fit the dial ellipse to points (N, 2) px: the entry point used by the reader.

    ``shape``: ``"ellipse"`` (Halir-Flusser, N >= 5), ``"circle"`` (Pratt, N >= 3, for a dial seen
    head-on) or ``"auto"``: a circle for 3-4 points (or when the ellipse is degenerate), and from 5
    points whichever of the circle and the ellipse wins :func:`select_circle_or_ellipse`
    (``noise_px``, the point noise in px if known, feeds that test). With ``refine`` the chosen
    algebraic fit seeds a Levenberg-Marquardt minimisation of the orthogonal distances
    (:func:`gauged.geometry.ellipse_refine.refine_ellipse`), kept only when it lowers the orthogonal
    RMS. Refinement is off by default: in the notch-keypoint regime (10-40 points, >= 180 degrees of
    arc, noise <= 1% of the radius) it does not measurably improve centre or angle accuracy, and on
    short noisy arcs it drifts to larger ellipses (figures in docs/geometry.md).

    Failures (stage ``"ellipse"``): ``too_few_points``, ``degenerate_conic``.
    """
    points = as_points(points)
    if shape == "ellipse":
        fitted = fit_ellipse_direct(points)
    elif shape == "circle":
        fitted = fit_circle(points)
    elif shape == "auto":
        circle = fit_circle(points)
        fitted = fit_ellipse_direct(points) if len(points) >= 5 else circle
        if not fitted and circle:  # e.g. only 3-4 distinct points among 5 or more
            fitted = circle
        elif fitted and circle and fitted is not circle:
            fitted = select_circle_or_ellipse(points, circle, fitted, noise_px)
    else:
        raise ValueError(f"unknown shape {shape!r}")
    if not fitted or not refine:
        return fitted
    is_circle = shape == "circle" or (shape == "auto" and fitted.a == fitted.b)
    return refine_ellipse(points, fitted, circle=is_circle, max_iterations=max_iterations)
