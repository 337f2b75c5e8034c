"""Robust angle -> value fit and the ScaleModel built from OCR markers."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from gauged.geometry.angles import unwrap, wrap_angle, wrap_to_pi
from gauged.geometry.dial_frame import point_at_dial_angle
from gauged.geometry.scale_fit import fit_angle_value, fit_scale_model, number_rings
from gauged.types import Ellipse, ScaleMarker, StageFailure

ELLIPSE = Ellipse(320.0, 240.0, 150.0, 110.0, 0.4)


def _markers(
    ellipse: Ellipse, start: float, end: float, values: np.ndarray, radius_fraction: float = 0.8
) -> list[ScaleMarker]:
    """Number markers printed at ``radius_fraction`` of the ring, evenly from start to end notch."""
    span = (end - start) % (2.0 * math.pi)
    angles = start + np.linspace(0.0, span, len(values))
    centre = np.array(ellipse.center)
    at = centre + radius_fraction * (point_at_dial_angle(ellipse, angles) - centre)
    return [
        ScaleMarker(text=f"{v:g}", value=float(v), box=(x - 6.0, y - 4.0, x + 6.0, y + 4.0))
        for v, (x, y) in zip(values, at, strict=True)
    ]


@pytest.mark.parametrize(("start_deg", "span_deg"), [(135.0, 270.0), (-150.0, 300.0), (180.0, 180.0), (100.0, 330.0)])
@pytest.mark.parametrize(("low", "high", "count"), [(0.0, 10.0, 6), (-1.0, 0.0, 5), (0.0, 600.0, 13), (20.0, 120.0, 3)])
def test_fit_scale_model_round_trip_over_swept_dials(
    start_deg: float, span_deg: float, low: float, high: float, count: int
) -> None:
    start = math.radians(start_deg)
    end = float(wrap_to_pi(start + math.radians(span_deg)))
    model = fit_scale_model(ELLIPSE, _markers(ELLIPSE, start, end, np.linspace(low, high, count)), start, end, unit="bar")
    assert model, model
    assert model.zero_angle == pytest.approx(wrap_angle(start, end))
    assert (model.min_value, model.max_value) == (pytest.approx(low, abs=1e-9), pytest.approx(high, abs=1e-9))
    assert model.inliers == count and all(m.inlier for m in model.markers)
    # A needle half way along the scale reads the middle value.
    assert model.value_at(float(wrap_to_pi(start + math.radians(span_deg) / 2.0))) == pytest.approx((low + high) / 2.0)
    assert model.unit == "bar"


def test_fit_angle_value_rejects_gross_outliers_and_refits() -> None:
    rng = np.random.default_rng(4)
    angles = np.radians(np.linspace(135.0, 405.0, 11))
    values = np.linspace(0.0, 100.0, 11)
    noisy = angles + rng.normal(0.0, math.radians(0.5), 11)
    values_bad = values.copy()
    values_bad[[2, 7]] = [2.0, 700.0]  # "20" read as "2", "70" read as "700"
    fit = fit_angle_value(noisy, values_bad)
    assert fit.inliers.tolist() == [i not in (2, 7) for i in range(11)]
    assert fit.slope == pytest.approx(100.0 / math.radians(270.0), rel=0.02)
    assert fit.rms_angle < math.radians(1.0)


@settings(max_examples=150, deadline=None, derandomize=True)
@given(
    n_inliers=st.integers(5, 15),
    outlier_fraction=st.floats(0.0, 0.4),
    span_deg=st.floats(180.0, 330.0),
    low=st.floats(-1000.0, 1000.0),
    value_range=st.floats(0.5, 2000.0),
    sign=st.sampled_from([1.0, -1.0]),
    seed=st.integers(0, 2**32 - 1),
)
def test_fit_angle_value_ignores_up_to_40_percent_gross_outliers(
    n_inliers: int, outlier_fraction: float, span_deg: float, low: float, value_range: float, sign: float, seed: int
) -> None:
    rng = np.random.default_rng(seed)
    n_outliers = int(math.floor(outlier_fraction * n_inliers / (1.0 - outlier_fraction)))  # <= 40% of all
    span = math.radians(span_deg)
    slope = sign * value_range / span
    true_angles = 2.0 + np.linspace(0.0, span, n_inliers)
    values = low + slope * (true_angles - 2.0)
    angles = true_angles + rng.uniform(-1.0, 1.0, n_inliers) * math.radians(1.0)
    # Gross outliers: OCR misreads, at least 10 tolerances (30 degrees) off the true line.
    out_angles = 2.0 + rng.uniform(0.0, span, n_outliers)
    offsets = rng.uniform(math.radians(30.0), span, n_outliers) * rng.choice([-1.0, 1.0], n_outliers)
    out_values = low + slope * (out_angles - 2.0 + offsets)
    fit = fit_angle_value(np.concatenate([angles, out_angles]), np.concatenate([values, out_values]))
    assert fit, fit
    assert fit.inliers.tolist() == [True] * n_inliers + [False] * n_outliers
    assert fit.slope == pytest.approx(slope, rel=0.05)


def test_fit_angle_value_random_sampling_is_seeded() -> None:
    angles = np.linspace(0.0, 4.0, 60)
    values = 3.0 * angles + 1.0
    values[::5] += 50.0
    a = fit_angle_value(angles, values, max_trials=100, rng=np.random.default_rng(7))
    b = fit_angle_value(angles, values, max_trials=100, rng=np.random.default_rng(7))
    assert a.slope == b.slope and np.array_equal(a.inliers, b.inliers)
    assert a.slope == pytest.approx(3.0) and a.inliers.sum() == 48


def test_number_rings_split_two_scales_outer_first_and_fit_each() -> None:
    start, end = math.radians(135.0), math.radians(45.0)
    bar = _markers(ELLIPSE, start, end, np.linspace(0.0, 10.0, 6), radius_fraction=0.8)
    psi = _markers(ELLIPSE, start, end, np.linspace(0.0, 145.0, 6), radius_fraction=1.15)
    mixed = [m for pair in zip(bar, psi, strict=True) for m in pair]
    outer, inner = number_rings(ELLIPSE, mixed)
    assert [m.value for m in outer] == [m.value for m in psi]
    assert [m.value for m in inner] == [m.value for m in bar]
    bar_scale = fit_scale_model(ELLIPSE, inner, start, end, unit="bar")
    psi_scale = fit_scale_model(ELLIPSE, outer, start, end, unit="psi")
    assert bar_scale.max_value == pytest.approx(10.0) and psi_scale.max_value == pytest.approx(145.0)
    needle = math.radians(270.0)
    assert psi_scale.value_at(needle) / bar_scale.value_at(needle) == pytest.approx(14.5)


def test_number_rings_both_inside_the_scale_ellipse() -> None:
    """Both scales printed inside the notch ring: the split is by radius, not by the ellipse."""
    start, end = math.radians(135.0), math.radians(45.0)
    main = _markers(ELLIPSE, start, end, np.linspace(0.0, 60.0, 7), radius_fraction=0.85)
    second = _markers(ELLIPSE, start, end, np.linspace(0.0, 8.0, 5), radius_fraction=0.55)
    outer, inner = number_rings(ELLIPSE, second + main)
    assert sorted(m.value for m in outer) == sorted(m.value for m in main)
    assert sorted(m.value for m in inner) == sorted(m.value for m in second)


def test_number_rings_one_ring_and_a_stray() -> None:
    """A single stray number (a serial number) does not make a ring of its own."""
    start, end = math.radians(135.0), math.radians(45.0)
    main = _markers(ELLIPSE, start, end, np.linspace(0.0, 10.0, 6), radius_fraction=0.8)
    stray = _markers(ELLIPSE, start, start, [952396.0], radius_fraction=0.3)
    assert number_rings(ELLIPSE, main + stray) == [main + stray]
    assert number_rings(ELLIPSE, []) == []


def test_fit_scale_model_uses_given_marker_angles() -> None:
    start, end = math.radians(135.0), math.radians(45.0)
    markers = [
        ScaleMarker(text=str(v), value=float(v), box=(0.0, 0.0, 1.0, 1.0), angle=float(wrap_to_pi(start + i * 0.5)))
        for i, v in enumerate([0, 1, 2, 3])
    ]
    model = fit_scale_model(ELLIPSE, markers, start, end)
    assert model.slope == pytest.approx(2.0)
    assert model.value_at(start) == pytest.approx(0.0)
    assert [m.angle for m in model.markers] == [m.angle for m in markers]


def _failure(result: object) -> tuple[str, str]:
    assert isinstance(result, StageFailure)
    return result.stage, result.reason


def test_fit_angle_value_too_few_markers() -> None:
    assert _failure(fit_angle_value(np.array([1.0]), np.array([5.0]))) == ("scale", "too_few_markers")
    assert _failure(fit_scale_model(ELLIPSE, [], 0.0, 1.0)) == ("scale", "too_few_markers")


def test_fit_angle_value_degenerate_fit() -> None:
    same_value = fit_angle_value(np.array([1.0, 2.0, 3.0]), np.array([5.0, 5.0, 5.0]))
    same_angle = fit_angle_value(np.array([2.0, 2.0, 2.0]), np.array([1.0, 5.0, 9.0]))
    assert _failure(same_value) == ("scale", "degenerate_fit")
    assert _failure(same_angle) == ("scale", "degenerate_fit")


def test_fit_angle_value_wrong_slope_sign() -> None:
    result = fit_angle_value(np.array([1.0, 2.0, 3.0]), np.array([9.0, 5.0, 1.0]), expected_sign=1)
    assert _failure(result) == ("scale", "wrong_slope_sign")
    assert fit_angle_value(np.array([1.0, 2.0, 3.0]), np.array([9.0, 5.0, 1.0]), expected_sign=-1).slope == -4.0


def test_fit_angle_value_too_few_inliers() -> None:
    # Four markers, no three on a line: every hypothesis gathers two.
    angles = np.array([1.0, 2.0, 3.0, 4.0])
    values = np.array([0.0, 10.0, 5.0, 40.0])
    assert _failure(fit_angle_value(angles, values, min_inliers=3)) == ("scale", "too_few_inliers")


def test_fit_angle_value_rejects_mismatched_inputs() -> None:
    with pytest.raises(ValueError, match="shape"):
        fit_angle_value(np.zeros(3), np.zeros(4))
    with pytest.raises(ValueError, match="finite"):
        fit_angle_value(np.array([0.0, np.nan]), np.zeros(2))


def test_unwrapped_marker_angles_are_continuous_across_the_image_branch_cut() -> None:
    # A scale from 135 to 45 degrees crosses +-180 degrees: unwrapping keeps the line straight.
    start, end = math.radians(135.0), math.radians(45.0)
    zero = wrap_angle(start, end)
    raw = wrap_to_pi(np.radians(np.linspace(135.0, 405.0, 7)))
    assert np.all(np.diff(unwrap(raw, zero)) > 0.0)


def test_scale_ends_carry_no_float_noise() -> None:
    """A scale from 0 reads 0..10, not -1.8e-15..10 (which `gauged read` printed for a real dial)."""
    start, end = math.radians(135.0), math.radians(45.0)
    for values in (np.linspace(0.0, 10.0, 6), np.linspace(0.0, 1.0, 11), np.linspace(-1.0, 0.0, 5)):
        model = fit_scale_model(ELLIPSE, _markers(ELLIPSE, start, end, values), start, end)
        assert (model.min_value, model.max_value) == (values[0], values[-1])
        assert all(math.copysign(1.0, v) == 1.0 for v in (model.min_value, model.max_value) if v == 0)  # no "-0"
