from __future__ import annotations

import doctest
import math

import pytest
from hypothesis import given
from hypothesis import strategies as st

import gauged.tracking.hampel
import gauged.tracking.response
import gauged.tracking.smoothers
import gauged.tracking.tracker
from gauged.tracking.smoothers import Ema, Passthrough, ScalarKalman, steady_state_gain


@pytest.mark.parametrize(
    "module", [gauged.tracking.smoothers, gauged.tracking.hampel, gauged.tracking.response, gauged.tracking.tracker])
def test_tracking_docstring_examples_run(module: object) -> None:
    failed, tried = doctest.testmod(module)  # type: ignore[arg-type]
    assert tried > 0 and failed == 0


@pytest.mark.parametrize(("q", "r", "dt"), [(0.1, 0.05, 0.1), (1.0, 0.1, 1.0), (0.01, 0.5, 0.033)])
def test_scalar_kalman_converges_to_steady_state_gain(q: float, r: float, dt: float) -> None:
    kf = ScalarKalman(q, r)
    kf.reset(0.0)
    for _ in range(2000):
        kf.update(0.0, dt)
    before = kf.value
    after = kf.update(1.0, dt)
    assert after - before == pytest.approx(steady_state_gain(q, r, dt), rel=1e-6)


def test_scalar_kalman_low_confidence_moves_less() -> None:
    sure, doubtful = ScalarKalman(0.1, 0.05), ScalarKalman(0.1, 0.05)
    for kf in (sure, doubtful):
        kf.reset(0.0)
    assert sure.update(1.0, 0.1, weight=1.0) > doubtful.update(1.0, 0.1, weight=0.2) > 0.0


def test_ema_ramp_lag_is_its_time_constant() -> None:
    ema = Ema(tau_s=1.0)
    ema.reset(0.0)
    dt = 0.01
    for i in range(1, 2001):
        ema.update(i * dt, dt)
    assert 20.0 - ema.value == pytest.approx(1.0, abs=0.01)


def test_passthrough_returns_the_measurement() -> None:
    p = Passthrough()
    p.reset(3.0)
    assert p.update(7.5, 0.1, weight=0.1) == 7.5


@pytest.mark.parametrize(("cls", "args"), [(ScalarKalman, (0.0, 1.0)), (ScalarKalman, (1.0, 0.0)), (Ema, (0.0,))])
def test_smoothers_reject_bad_arguments(cls: type, args: tuple[float, ...]) -> None:
    with pytest.raises(ValueError):
        cls(*args)


measurements = st.lists(
    st.tuples(st.floats(-1e3, 1e3), st.floats(0.0, 5.0), st.floats(0.0, 1.0)), min_size=1, max_size=40)


@given(measurements)
def test_smoothers_stay_within_the_measured_range(steps: list[tuple[float, float, float]]) -> None:
    # No overshoot: every estimate is a convex combination of the start and the measurements, which
    # is what keeps a smoothed value from crossing an alarm limit that no reading crossed.
    for smoother in (ScalarKalman(0.5, 0.1), Ema(1.0), Passthrough()):
        smoother.reset(steps[0][0])
        seen = [steps[0][0]]
        for value, dt, weight in steps:
            seen.append(value)
            estimate = smoother.update(value, dt, weight)
            assert math.isfinite(estimate)
            assert min(seen) - 1e-9 <= estimate <= max(seen) + 1e-9


def test_smoothing_config_defaults_document_every_field() -> None:
    from gauged.tracking.config import SmoothingConfig

    for name, field in SmoothingConfig.model_fields.items():
        assert field.description and not field.is_required(), name
