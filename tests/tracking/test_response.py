from __future__ import annotations

import pytest

from gauged.tracking.config import SmoothingConfig
from gauged.tracking.response import characterize

# The figures docs/alarms.md states, with the bound each must stay within (span 10, 5 %/s ramp).
# (method, fps, first move s, 90 % s, settled s, ramp lag s, noise ratio at most)
STATED = [
    ("kalman", 10.0, 0.2, 0.4, 0.7, 0.12, 0.55),
    ("kalman", 1.0, 2.0, 2.0, 3.0, 0.21, 0.90),
    ("kalman", 30.0, 0.067, 0.23, 0.4, 0.08, 0.45),
    ("ema", 10.0, 0.2, 2.3, 4.0, 0.95, 0.20),
    ("none", 10.0, 0.2, 0.2, 0.2, 0.0, 1.0),
]


@pytest.mark.parametrize(("method", "fps", "first", "t90", "settle", "lag", "noise"), STATED)
def test_characterize_defaults_match_the_documented_figures(
        method: str, fps: float, first: float, t90: float, settle: float, lag: float, noise: float) -> None:
    figures = characterize(SmoothingConfig(method=method), fps=fps)  # type: ignore[arg-type]
    measured = (figures.step_first_move_s, figures.step_90_s, figures.step_settle_s, figures.ramp_lag_s)
    assert measured == pytest.approx((first, t90, settle, lag), abs=0.01)
    assert figures.noise_ratio <= noise


def test_characterize_step_waits_for_the_hampel_window() -> None:
    for window, frames in ((1, 0), (3, 1), (5, 2), (9, 4)):
        figures = characterize(SmoothingConfig(method="none", hampel_window=window), fps=10.0)
        assert figures.step_first_move_s == pytest.approx(frames / 10.0)


def test_characterize_smaller_process_noise_smooths_more_and_lags_more() -> None:
    default = characterize(SmoothingConfig(), fps=10.0)
    calm = characterize(SmoothingConfig(process_noise_per_s=0.02), fps=10.0)
    assert calm.noise_ratio < default.noise_ratio and calm.ramp_lag_s > default.ramp_lag_s
