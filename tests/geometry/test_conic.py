"""Conic coefficients <-> ellipse parameters."""

from __future__ import annotations

import math

import numpy as np
import pytest

from gauged.geometry.conic import conic_to_ellipse, ellipse_matrix, ellipse_to_conic, normalized_ellipse
from gauged.types import Ellipse, StageFailure


def _assert_same_ellipse(got: Ellipse, want: Ellipse, rel: float) -> None:
    assert got.cx == pytest.approx(want.cx, abs=rel * want.a)
    assert got.cy == pytest.approx(want.cy, abs=rel * want.a)
    assert got.a == pytest.approx(want.a, rel=rel)
    assert got.b == pytest.approx(want.b, rel=rel)
    if want.a > want.b * (1.0 + 1e-3):  # theta is meaningless for a circle
        diff = (got.theta - want.theta + math.pi / 2.0) % math.pi - math.pi / 2.0
        assert abs(diff) < rel * 10.0


@pytest.mark.parametrize("theta", np.linspace(0.0, math.pi, 7, endpoint=False))
@pytest.mark.parametrize("ratio", [0.1, 0.5, 0.9, 1.0])
@pytest.mark.parametrize(("cx", "cy", "a"), [(0.0, 0.0, 1.0), (640.0, 480.0, 150.0), (-30.0, 2000.0, 4000.0)])
def test_conic_round_trip_over_swept_ellipses(theta: float, ratio: float, cx: float, cy: float, a: float) -> None:
    truth = Ellipse(cx, cy, a, a * ratio, float(theta))
    _assert_same_ellipse(conic_to_ellipse(ellipse_to_conic(truth)), truth, rel=1e-9)


def test_conic_vanishes_on_the_ellipse_and_is_scale_free() -> None:
    truth = Ellipse(12.0, -7.0, 9.0, 4.0, 2.0)
    points = truth.point_at(np.linspace(0.0, 6.0, 25))
    a, b, c, d, e, f = ellipse_to_conic(truth)
    x, y = points[:, 0], points[:, 1]
    assert np.allclose(a * x * x + b * x * y + c * y * y + d * x + e * y + f, 0.0, atol=1e-12)
    homogeneous = np.hstack([points, np.ones((25, 1))])
    assert np.allclose(np.einsum("ni,ij,nj->n", homogeneous, ellipse_matrix(truth), homogeneous), 0.0, atol=1e-12)
    _assert_same_ellipse(conic_to_ellipse(-3.7 * ellipse_to_conic(truth)), truth, rel=1e-9)


def test_normalized_ellipse_orders_axes_and_theta() -> None:
    e = normalized_ellipse(1.0, 2.0, -3.0, 5.0, -0.25)
    assert (e.a, e.b) == (5.0, 3.0)
    assert e.theta == pytest.approx(math.pi / 2.0 - 0.25)
    assert 0.0 <= normalized_ellipse(0, 0, 2, 1, -1e-18).theta < math.pi


@pytest.mark.parametrize(
    ("conic", "what"),
    [
        ((1.0, 0.0, -1.0, 0.0, 0.0, -1.0), "hyperbola"),
        ((1.0, 0.0, 0.0, 0.0, -1.0, 0.0), "parabola"),
        ((1.0, 0.0, 1.0, 0.0, 0.0, 1.0), "imaginary ellipse"),
        ((1.0, 0.0, 1.0, 0.0, 0.0, 0.0), "single point"),
        ((0.0, 0.0, 0.0, 1.0, 1.0, 1.0), "line"),
        ((float("nan"), 0.0, 1.0, 0.0, 0.0, -1.0), "non-finite"),
    ],
)
def test_conic_to_ellipse_degenerate_conic(conic: tuple[float, ...], what: str) -> None:
    result = conic_to_ellipse(np.array(conic))
    assert isinstance(result, StageFailure), what
    assert not result
    assert (result.stage, result.reason) == ("ellipse", "degenerate_conic")


def test_conic_to_ellipse_rejects_wrong_shape() -> None:
    with pytest.raises(ValueError, match="shape"):
        conic_to_ellipse(np.zeros(5))
