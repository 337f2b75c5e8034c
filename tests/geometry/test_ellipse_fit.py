"""Ellipse and circle fits: exact recovery, the noise acceptance figures, failures."""

from __future__ import annotations

import math

import numpy as np
import pytest

from gauged.geometry.ellipse_distance import orthogonal_distance
from gauged.geometry.dial_frame import normalized_radius
from gauged.geometry.ellipse_fit import fit_circle, fit_ellipse, fit_ellipse_direct, fit_ellipses_direct
from gauged.types import Ellipse, StageFailure


def _assert_close(got: Ellipse, want: Ellipse, rel: float) -> None:
    assert got, got
    assert math.hypot(got.cx - want.cx, got.cy - want.cy) <= rel * want.a
    assert got.a == pytest.approx(want.a, rel=rel)
    assert got.b == pytest.approx(want.b, rel=rel)
    if want.a > want.b * 1.01:
        assert abs((got.theta - want.theta + math.pi / 2) % math.pi - math.pi / 2) <= rel


@pytest.mark.parametrize("theta", [0.0, 0.4, 1.2, 2.0, 3.0])
@pytest.mark.parametrize("ratio", [0.3, 0.7, 0.98])
@pytest.mark.parametrize(("a", "centre"), [(20.0, (30.0, 40.0)), (150.0, (320.0, 240.0)), (600.0, (1900.0, 1000.0))])
@pytest.mark.parametrize(("arc_deg", "n"), [(360.0, 5), (270.0, 12), (120.0, 40)])
def test_fit_ellipse_direct_recovers_noise_free_ellipses(
    theta: float, ratio: float, a: float, centre: tuple[float, float], arc_deg: float, n: int
) -> None:
    truth = Ellipse(centre[0], centre[1], a, a * ratio, theta)
    points = truth.point_at(0.3 + np.linspace(0.0, math.radians(arc_deg), n, endpoint=arc_deg < 360.0))
    _assert_close(fit_ellipse_direct(points), truth, rel=1e-6)
    _assert_close(fit_ellipse(points, refine=True), truth, rel=1e-6)


def _centre_errors(truth: Ellipse, sigma: float, seeds: int, **kwargs) -> np.ndarray:
    t = np.linspace(0.0, math.radians(270.0), 12)
    errors = []
    for seed in range(seeds):
        points = truth.point_at(t) + np.random.default_rng(seed).normal(0.0, sigma, (12, 2))
        fit = fit_ellipse(points, **kwargs)
        errors.append(math.hypot(fit.cx - truth.cx, fit.cy - truth.cy))
    return np.array(errors)


def _crlb_centre_rms(truth: Ellipse, sigma: float) -> float:
    """Cramer-Rao bound on the RMS centre error of any unbiased 5-parameter fit (numeric Jacobian)."""
    points = truth.point_at(np.linspace(0.0, math.radians(270.0), 12))
    p0 = np.array([truth.cx, truth.cy, truth.a, truth.b, truth.theta])

    def distances(p: np.ndarray) -> np.ndarray:
        return orthogonal_distance(Ellipse(*p), points)

    step = 1e-6
    jac = np.stack([(distances(p0 + step * e) - distances(p0 - step * e)) / (2 * step) for e in np.eye(5)], axis=1)
    cov = sigma**2 * np.linalg.pinv(jac.T @ jac)
    return float(math.sqrt(cov[0, 0] + cov[1, 1]))


@pytest.mark.parametrize("truth", [Ellipse(320.0, 240.0, 150.0, 150.0, 0.0), Ellipse(320.0, 240.0, 150.0, 110.0, 0.5)])
def test_fit_ellipse_centre_acceptance_with_1px_noise(truth: Ellipse) -> None:
    """12 points over 270 degrees of a 150 px dial, 1 px Gaussian noise per coordinate, 200 seeds.

    Measured (HF = Halir-Flusser, refine = + Levenberg-Marquardt on orthogonal distances):
    circle truth  HF worst 1.73 p95 1.25 px, refine worst 1.73 p95 1.25 px, CRLB p95 1.06 px;
    b=110 truth   HF worst 1.92 p95 1.20 px, refine worst 2.12 p95 1.19 px, CRLB p95 1.21 px.
    "Centre within 1 px on every seed" is below the Cramer-Rao bound (P < 1e-6 for 200 seeds),
    so no estimator meets it; the fit is held to the bound instead.
    """
    direct = _centre_errors(truth, 1.0, 200, refine=False)
    refined = _centre_errors(truth, 1.0, 200, refine=True)
    crlb = _crlb_centre_rms(truth, 1.0)
    for errors in (direct, refined):
        worst, p95, rms = errors.max(), np.percentile(errors, 95), math.sqrt(np.mean(errors**2))
        assert worst < 2.5, f"worst {worst:.3f} px"
        assert p95 < 1.35, f"p95 {p95:.3f} px"
        assert rms < 1.2 * crlb, f"rms {rms:.3f} px vs Cramer-Rao {crlb:.3f} px"
        # The "centre within 1 px", read as the typical (RMS and median) error.
        assert rms < 1.0 and np.median(errors) < 1.0, f"rms {rms:.3f} px, median {np.median(errors):.3f} px"


def test_fit_ellipse_centre_within_1px_on_every_seed_at_half_pixel_noise() -> None:
    # The 1 px requirement holds robustly once the noise is 0.5 px (measured worst 0.96 px).
    errors = _centre_errors(Ellipse(320.0, 240.0, 150.0, 110.0, 0.5), 0.5, 200)
    assert errors.max() < 1.0, f"worst {errors.max():.3f} px, p95 {np.percentile(errors, 95):.3f} px"


@pytest.mark.parametrize("method", ["pratt", "kasa"])
@pytest.mark.parametrize("n", [3, 4, 20])
def test_fit_circle_recovers_noise_free_circles(method: str, n: int) -> None:
    truth = Ellipse(-40.0, 75.0, 33.0, 33.0, 0.0)
    points = truth.point_at(np.linspace(0.5, 2.5, n))
    _assert_close(fit_circle(points, method=method), truth, rel=1e-9)


def test_fit_circle_pratt_is_less_biased_than_kasa_on_short_arcs() -> None:
    # Kasa's fit shrinks circles on short arcs (Chernov 2010, sec. 5.3); Pratt's does not.
    truth = Ellipse(0.0, 0.0, 100.0, 100.0, 0.0)
    t = np.linspace(0.0, math.radians(60.0), 30)
    radii = {"pratt": [], "kasa": []}
    for seed in range(100):
        points = truth.point_at(t) + np.random.default_rng(seed).normal(0.0, 2.0, (30, 2))
        for method in radii:
            radii[method].append(fit_circle(points, method=method).a)
    assert abs(np.mean(radii["pratt"]) - 100.0) < 0.5 * abs(np.mean(radii["kasa"]) - 100.0)


def test_fit_ellipse_auto_uses_a_circle_below_five_points() -> None:
    truth = Ellipse(10.0, 10.0, 5.0, 5.0, 0.0)
    fit = fit_ellipse(truth.point_at(np.array([0.0, 1.0, 2.0, 4.0])), shape="auto")
    _assert_close(fit, truth, rel=1e-9)
    assert fit.a == fit.b


def test_fit_ellipse_auto_picks_the_right_model() -> None:
    t = np.linspace(0.0, math.radians(270.0), 12)
    tilted = Ellipse(320.0, 240.0, 150.0, 130.0, 0.5)
    frontal = Ellipse(320.0, 240.0, 150.0, 150.0, 0.0)
    chosen_circle = {"tilted": 0, "frontal": 0}
    for seed in range(50):
        noise = np.random.default_rng(seed).normal(0.0, 1.0, (12, 2))
        chosen_circle["tilted"] += fit_ellipse(tilted.point_at(t) + noise, shape="auto").b == 150.0
        fit = fit_ellipse(frontal.point_at(t) + noise, shape="auto", noise_px=1.0)
        chosen_circle["frontal"] += fit.a == fit.b
    assert chosen_circle["tilted"] == 0
    assert chosen_circle["frontal"] >= 35  # measured 40/50; AIC keeps some noise-shaped ellipses


def test_fit_ellipse_refine_never_raises_the_orthogonal_rms() -> None:
    truth = Ellipse(0.0, 0.0, 80.0, 50.0, 0.7)
    for seed in range(20):
        rng = np.random.default_rng(seed)
        points = truth.point_at(rng.uniform(0.0, 4.0, 15)) + rng.normal(0.0, 3.0, (15, 2))
        direct = fit_ellipse(points, refine=False)
        refined = fit_ellipse(points, refine=True)
        rms_direct = math.sqrt(np.mean(orthogonal_distance(direct, points) ** 2))
        rms_refined = math.sqrt(np.mean(orthogonal_distance(refined, points) ** 2))
        assert rms_refined <= rms_direct + 1e-12


@pytest.mark.parametrize(("shape", "n"), [("ellipse", 4), ("ellipse", 0), ("circle", 2), ("auto", 2)])
def test_fit_ellipse_too_few_points(shape: str, n: int) -> None:
    points = Ellipse(0.0, 0.0, 5.0, 3.0, 0.0).point_at(np.arange(n, dtype=float))
    result = fit_ellipse(points, shape=shape)
    assert isinstance(result, StageFailure)
    assert (result.stage, result.reason) == ("ellipse", "too_few_points")


@pytest.mark.parametrize(
    "points",
    [
        np.stack([np.linspace(0.0, 10.0, 8), 2.0 * np.linspace(0.0, 10.0, 8) + 1.0], axis=1),  # collinear
        np.repeat(np.array([[1.0, 2.0], [3.0, 5.0], [4.0, 1.0]]), 3, axis=0),  # 3 distinct points
        np.zeros((6, 2)),
    ],
    ids=["collinear", "duplicates", "one-point"],
)
def test_fit_ellipse_degenerate_conic(points: np.ndarray) -> None:
    result = fit_ellipse_direct(points)
    assert isinstance(result, StageFailure)
    assert (result.stage, result.reason) == ("ellipse", "degenerate_conic")


@pytest.mark.parametrize("method", ["pratt", "kasa"])
def test_fit_circle_degenerate_conic_for_collinear_points(method: str) -> None:
    points = np.stack([np.linspace(0.0, 10.0, 6), np.full(6, 3.0)], axis=1)
    result = fit_circle(points, method=method)
    assert isinstance(result, StageFailure)
    assert result.reason == "degenerate_conic"


def test_fit_ellipse_rejects_bad_arguments() -> None:
    with pytest.raises(ValueError):
        fit_ellipse(np.zeros((10, 3)))
    with pytest.raises(ValueError, match="shape"):
        fit_ellipse(np.random.default_rng(0).normal(size=(10, 2)), shape="square")  # type: ignore[arg-type]


def test_fit_ellipse_auto_falls_back_to_a_circle_when_the_ellipse_is_degenerate() -> None:
    truth = Ellipse(0.0, 0.0, 10.0, 10.0, 0.0)
    points = np.repeat(truth.point_at(np.array([0.0, 2.0, 4.0])), 2, axis=0)  # 6 points, 3 distinct
    assert fit_ellipse_direct(points).reason == "degenerate_conic"
    _assert_close(fit_ellipse(points, shape="auto"), truth, rel=1e-9)


def test_fit_ellipses_direct_agrees_with_one_fit_at_a_time():
    rng = np.random.default_rng(3)
    truth = Ellipse(200.0, 210.0, 120.0, 80.0, 0.4)
    on_ring = truth.point_at(rng.uniform(0.0, 2 * math.pi, 9)) + rng.normal(0.0, 1.0, (9, 2))
    scattered = rng.normal(200.0, 60.0, (9, 2))  # many 5-point samples of these are hyperbolas
    samples = [on_ring[:5], on_ring[4:], scattered[:5], scattered[3:8], scattered[4:]]
    samples.append(np.repeat(on_ring[:1], 5, axis=0))  # one point five times
    samples.append(np.stack([np.arange(5.0), 2.0 * np.arange(5.0)], axis=1))  # a line
    batch = fit_ellipses_direct(np.stack(samples))
    radius = batch.normalized_radius(on_ring)
    for k, sample in enumerate(samples):
        one = fit_ellipse_direct(sample)
        assert bool(one) == bool(batch.ok[k]), k
        if one:
            assert batch.a[k] == pytest.approx(one.a, rel=1e-9) and batch.b[k] == pytest.approx(one.b, rel=1e-9)
            assert np.allclose(batch.centre[k], one.center, rtol=1e-9)
            assert np.allclose(radius[k], normalized_radius(one, on_ring), rtol=1e-9)
    assert batch.ok[:2].all() and not batch.ok[5:].any()
    assert np.allclose(batch.normalized_radius(samples[0])[0], 1.0, atol=1e-6)  # five points fix the conic
