"""Conic coefficients <-> geometric ellipse parameters.

A conic is the coefficient vector ``(A, B, C, D, E, F)`` of

    A x^2 + B x y + C y^2 + D x + E y + F = 0

in pixel coordinates (see :mod:`gauged.types`). Only the direction of the vector matters. An
ellipse needs ``4 A C - B^2 > 0`` and a real (non-empty) point set.

The conversion goes through the symmetric matrix form ``(p - c)^T Q (p - c) = k`` with
``Q = [[A, B/2], [B/2, C]]``: the centre solves ``2 Q c = -(D, E)``, the eigenvectors of ``Q`` are
the axes and ``sqrt(k / lambda_i)`` the semi-axes (e.g. Hartley & Zisserman, *Multiple View Geometry*,
2nd ed., sec. 2.2.3; using ``eigh`` on the 2x2 form is better conditioned than the closed-form
expressions in terms of ``A..F``).

Example:
    >>> from gauged.types import Ellipse
    >>> conic = ellipse_to_conic(Ellipse(10.0, 20.0, 5.0, 3.0, 0.5))
    >>> e = conic_to_ellipse(conic)
    >>> [round(v, 9) for v in (e.cx, e.cy, e.a, e.b, e.theta)]
    [10.0, 20.0, 5.0, 3.0, 0.5]
"""

from __future__ import annotations

import math

import numpy as np

from gauged.types import Ellipse, StageFailure

STAGE = "ellipse"


def normalized_ellipse(cx: float, cy: float, a: float, b: float, theta: float) -> Ellipse:
    """An :class:`Ellipse` with ``a >= b > 0`` and ``theta`` in ``[0, pi)``, from any sign/order of axes."""
    a, b = abs(float(a)), abs(float(b))
    if b > a:
        a, b = b, a
        theta += 0.5 * math.pi
    theta = float(np.mod(theta, math.pi))
    if theta >= math.pi:  # np.mod can round up to exactly pi
        theta = 0.0
    return Ellipse(float(cx), float(cy), a, b, theta)


def ellipse_to_conic(ellipse: Ellipse) -> np.ndarray:
    """Conic coefficients (6,) float64 ``(A, B, C, D, E, F)`` of ``ellipse``, scaled so ``A + C = 1``."""
    c, s = math.cos(ellipse.theta), math.sin(ellipse.theta)
    rot = np.array([[c, -s], [s, c]])
    q = rot @ np.diag([1.0 / ellipse.a**2, 1.0 / ellipse.b**2]) @ rot.T
    centre = np.array([ellipse.cx, ellipse.cy])
    qc = q @ centre
    conic = np.array([q[0, 0], 2.0 * q[0, 1], q[1, 1], -2.0 * qc[0], -2.0 * qc[1], centre @ qc - 1.0])
    return conic / (q[0, 0] + q[1, 1])


def conic_to_ellipse(conic: np.ndarray) -> Ellipse | StageFailure:
    """Geometric parameters of the ellipse ``conic`` (6,) = ``(A, B, C, D, E, F)``.

    Returns ``StageFailure("ellipse", "degenerate_conic")`` for a conic that is not a real ellipse
    (parabola, hyperbola, imaginary ellipse, a point, or non-finite coefficients).
    """
    conic = np.asarray(conic, dtype=float)
    if conic.shape != (6,):
        raise ValueError(f"conic must have shape (6,), got {conic.shape}")
    if not np.all(np.isfinite(conic)):
        return StageFailure(STAGE, "degenerate_conic", "non-finite conic coefficients")
    conic = conic / np.linalg.norm(conic) if np.any(conic) else conic
    a_, b_, c_, d_, e_, f_ = conic
    q = np.array([[a_, 0.5 * b_], [0.5 * b_, c_]])
    det = a_ * c_ - 0.25 * b_ * b_
    # Relative test: det against the squared size of Q, so the threshold does not depend on scaling.
    if det <= 1e-14 * (a_ * a_ + 0.5 * b_ * b_ + c_ * c_):
        return StageFailure(STAGE, "degenerate_conic", f"not an ellipse: 4AC - B^2 = {4.0 * det:.3g}")
    centre = np.linalg.solve(2.0 * q, -np.array([d_, e_]))
    # Value of the conic at its centre; the ellipse is (p - c)^T Q (p - c) = k with k = -that.
    k = -(f_ + 0.5 * (d_ * centre[0] + e_ * centre[1]))
    lambdas, vectors = np.linalg.eigh(q)  # ascending: the first is the major axis when k/lambda > 0
    if lambdas[0] * k <= 0.0 or lambdas[1] * k <= 0.0:
        return StageFailure(STAGE, "degenerate_conic", "imaginary or point ellipse")
    semi = np.sqrt(k / lambdas)
    if not np.all(np.isfinite(semi)) or not np.all(np.isfinite(centre)):
        return StageFailure(STAGE, "degenerate_conic", "non-finite ellipse parameters")
    major = vectors[:, 0] if semi[0] >= semi[1] else vectors[:, 1]
    theta = math.atan2(major[1], major[0])
    return normalized_ellipse(centre[0], centre[1], max(semi), min(semi), theta)


def conic_forms(conics: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """:func:`conic_to_ellipse` of K conics (K, 6) at once, as the matrix form RANSAC scores with.

    Returns ``(centre (K, 2), form (K, 2, 2), a (K,), b (K,), ok (K,))``: the ellipse is
    ``(p - centre)^T form (p - centre) = 1`` with semi-axes ``a >= b``; ``ok`` is False where
    :func:`conic_to_ellipse` fails (the same tests), and those rows are meaningless.
    """
    conics = np.asarray(conics, dtype=float)
    finite = np.all(np.isfinite(conics), axis=1)
    conics = np.where(finite[:, None], conics, 0.0)
    norms = np.linalg.norm(conics, axis=1)
    conics = conics / np.where(norms > 0.0, norms, 1.0)[:, None]
    a_, b_, c_, d_, e_, f_ = conics.T
    det = a_ * c_ - 0.25 * b_ * b_
    ok = finite & (det > 1e-14 * (a_ * a_ + 0.5 * b_ * b_ + c_ * c_))
    safe = np.where(ok, det, 1.0)
    # The centre solves 2 Q c = -(D, E) (Cramer's rule on the 2x2 system).
    cx = (-d_ * c_ + 0.5 * b_ * e_) / (2.0 * safe)
    cy = (-e_ * a_ + 0.5 * b_ * d_) / (2.0 * safe)
    k = -(f_ + 0.5 * (d_ * cx + e_ * cy))
    # Eigenvalues of Q = [[A, B/2], [B/2, C]], smaller first.
    mid, half = 0.5 * (a_ + c_), np.hypot(0.5 * (a_ - c_), 0.5 * b_)
    lam_small, lam_large = mid - half, mid + half
    ok &= (lam_small * k > 0.0) & (lam_large * k > 0.0)
    k = np.where(ok, k, 1.0)
    with np.errstate(invalid="ignore", divide="ignore"):
        semi = np.sqrt(np.stack([k / lam_small, k / lam_large]))  # the conic's sign is arbitrary
    semi_major, semi_minor = semi.max(axis=0), semi.min(axis=0)
    ok &= np.isfinite(semi_major) & np.isfinite(semi_minor) & np.isfinite(cx) & np.isfinite(cy)
    form = np.stack([np.stack([a_, 0.5 * b_], axis=1), np.stack([0.5 * b_, c_], axis=1)], axis=1) / k[:, None, None]
    return np.stack([cx, cy], axis=1), form, semi_major, semi_minor, ok


def ellipse_matrix(ellipse: Ellipse) -> np.ndarray:
    """The symmetric 3x3 conic matrix ``C`` with ``[x, y, 1] C [x, y, 1]^T = 0`` on the ellipse."""
    a_, b_, c_, d_, e_, f_ = ellipse_to_conic(ellipse)
    return np.array([[a_, 0.5 * b_, 0.5 * d_], [0.5 * b_, c_, 0.5 * e_], [0.5 * d_, 0.5 * e_, f_]])
