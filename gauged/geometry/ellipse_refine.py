"""Geometric refinement of an ellipse: least squares on orthogonal distances.

The algebraic fits of :mod:`gauged.geometry.ellipse_fit` minimise a distance that weighs points
unequally around the curve and is biased on partial arcs. This module minimises the sum of squared
*orthogonal* distances over the five parameters ``(cx, cy, a, b, theta)`` with Levenberg-Marquardt
(``scipy.optimize.least_squares(method="lm")``, i.e. MINPACK), the "geometric fit" of W. Gander,
G. Golub and R. Strebel, "Least-squares fitting of circles and ellipses", BIT 34 (1994), sec. 3-4,
but with the closest-point parameters eliminated: each residual is the signed distance
``r_i = n_i . (x_i - e(t_i))`` with ``t_i`` the exact closest point
(:func:`gauged.geometry.ellipse_distance.project_to_ellipse`). Because ``t_i`` minimises the
distance, ``dr_i/dt_i = 0`` and the Jacobian row is simply ``-n_i . de(t_i)/dp`` (the "variable
projection" shortcut of S. J. Ahn et al., "Least-squares orthogonal distances fitting of circle,
sphere, ellipse, hyperbola, and parabola", Pattern Recognition 34 (2001), eq. 21).

For a circle (``circle=True``) the residual is ``|x_i - c| - R`` over ``(cx, cy, R)``.

Example:
    >>> from gauged.types import Ellipse
    >>> truth = Ellipse(50.0, 60.0, 30.0, 20.0, 1.0)
    >>> start = Ellipse(52.0, 58.0, 28.0, 21.0, 0.9)
    >>> fit = refine_ellipse(truth.point_at(np.linspace(0.0, 6.0, 9)), start)
    >>> [round(v, 6) for v in (fit.cx, fit.cy, fit.a, fit.b, fit.theta)]
    [50.0, 60.0, 30.0, 20.0, 1.0]
"""

from __future__ import annotations

import numpy as np
from scipy.optimize import least_squares

from gauged.geometry.conic import normalized_ellipse
from gauged.geometry.dial_frame import as_points, rectifying_matrix
from gauged.geometry.ellipse_distance import project_to_ellipse
from gauged.types import Ellipse

# A refinement that inflates the major axis this much has drifted towards a straight line (the
# geometric optimum of a short, noisy arc); the algebraic seed is the better answer then.
_MAX_GROWTH = 10.0


def _ellipse_of(p: np.ndarray) -> Ellipse:
    return normalized_ellipse(p[0], p[1], p[2], p[3], p[4])


def _ellipse_residuals(p: np.ndarray, points: np.ndarray) -> np.ndarray:
    if p[2] == 0.0 or p[3] == 0.0:  # a collapsed axis has no closest points; steer the solver away
        return np.full(len(points), 1e6)
    return project_to_ellipse(_ellipse_of(p), points).distance


def _ellipse_jacobian(p: np.ndarray, points: np.ndarray) -> np.ndarray:
    """Rows ``-n_i . de/dp`` at the closest points (see the module docstring), in the raw parameters."""
    cx, cy, a, b, theta = p
    if a == 0.0 or b == 0.0:
        return np.zeros((len(points), 5))
    ellipse = _ellipse_of(p)
    closest = project_to_ellipse(ellipse, points).points - np.array([cx, cy])
    # The outward normal is the gradient of the implicit form, whatever the parametrisation.
    normal = closest @ rectifying_matrix(ellipse) @ rectifying_matrix(ellipse)
    normal /= np.linalg.norm(normal, axis=1, keepdims=True)
    # Parameter t of each closest point in the raw parametrisation (a, b unordered, any sign).
    u = np.array([np.cos(theta), np.sin(theta)])
    v = np.array([-np.sin(theta), np.cos(theta)])
    cos_t = (closest @ u) / a
    sin_t = (closest @ v) / b
    de_dtheta = (a * cos_t)[:, None] * v - (b * sin_t)[:, None] * u
    jac = np.empty((len(points), 5))
    jac[:, :2] = -normal
    jac[:, 2] = -cos_t * (normal @ u)
    jac[:, 3] = -sin_t * (normal @ v)
    jac[:, 4] = -np.sum(normal * de_dtheta, axis=1)
    return jac


def _circle_residuals(p: np.ndarray, points: np.ndarray) -> np.ndarray:
    return np.hypot(points[:, 0] - p[0], points[:, 1] - p[1]) - abs(p[2])


def _circle_jacobian(p: np.ndarray, points: np.ndarray) -> np.ndarray:
    rel = points - p[:2]
    dist = np.maximum(np.linalg.norm(rel, axis=1, keepdims=True), 1e-300)
    d_radius = -1.0 if p[2] >= 0.0 else 1.0  # the residual uses |R|
    return np.hstack([-rel / dist, np.full((len(points), 1), d_radius)])


def rms_orthogonal_distance(ellipse: Ellipse, points: np.ndarray) -> float:
    """Root-mean-square orthogonal distance (px) of points (N, 2) to ``ellipse``."""
    return float(np.sqrt(np.mean(project_to_ellipse(ellipse, as_points(points)).distance ** 2)))


def refine_ellipse(
    points: np.ndarray, initial: Ellipse, *, circle: bool = False, max_iterations: int = 50
) -> Ellipse:
    """Ellipse (or circle) minimising the orthogonal distances to points (N, 2) px, started at ``initial``.

    Works in coordinates centred on the points and scaled to unit RMS radius. Returns ``initial``
    unchanged when there are no more points than parameters, when the solver fails, when the result
    does not lower the RMS orthogonal distance, or when it runs off towards a line (major axis more
    than 10x the initial one).
    """
    points = as_points(points)
    n_params = 3 if circle else 5
    if len(points) <= n_params:
        return initial
    mean = points.mean(axis=0)
    scale = float(np.sqrt(np.mean(np.sum((points - mean) ** 2, axis=1)))) or 1.0
    norm = (points - mean) / scale
    start = [(initial.cx - mean[0]) / scale, (initial.cy - mean[1]) / scale, initial.a / scale]
    if circle:
        fun, jac = _circle_residuals, _circle_jacobian
    else:
        start += [initial.b / scale, initial.theta]
        fun, jac = _ellipse_residuals, _ellipse_jacobian
    try:
        result = least_squares(
            fun, np.array(start), jac=jac, args=(norm,), method="lm", max_nfev=max_iterations * (n_params + 1)
        )
    except (ValueError, np.linalg.LinAlgError):
        return initial
    p = result.x
    if not np.all(np.isfinite(p)):
        return initial
    if circle:
        refined = normalized_ellipse(p[0] * scale + mean[0], p[1] * scale + mean[1], p[2] * scale, p[2] * scale, 0.0)
    else:
        refined = normalized_ellipse(p[0] * scale + mean[0], p[1] * scale + mean[1], p[2] * scale, p[3] * scale, p[4])
    if refined.b <= 0.0 or refined.a > _MAX_GROWTH * initial.a:
        return initial
    if rms_orthogonal_distance(refined, points) >= rms_orthogonal_distance(initial, points):
        return initial
    return refined
