"""Configuration of per-gauge smoothing: outlier rejection, plausibility and the smoother.

Noise levels left out are derived from the gauge's scale span (``max - min``), so one default suits a
0-10 bar gauge and a 0-600 psi gauge alike. See ``docs/alarms.md`` for the chain and its measured
step response and ramp lag.
"""

from __future__ import annotations

from typing import Literal

from pydantic import BaseModel, ConfigDict, Field

# Fractions of the scale span used when the config leaves a noise level out (see docs/alarms.md).
DEFAULT_PROCESS_NOISE_SPAN_FRACTION = 0.01
DEFAULT_MEASUREMENT_NOISE_SPAN_FRACTION = 0.005


class SmoothingConfig(BaseModel):
    """How raw readings of one gauge become the published value (all times are frame times)."""

    model_config = ConfigDict(extra="forbid")

    method: Literal["kalman", "ema", "none"] = Field(
        "kalman", description="Smoother after outlier rejection: 1-D Kalman filter, EMA, or none.")
    hampel_window: int = Field(
        5, ge=1, description="Readings in the median window of the Hampel outlier filter (1 disables it). "
        "A real step is followed after (hampel_window - 1) // 2 frames.")
    hampel_k: float = Field(3.0, gt=0, description="A reading further than k scaled MADs from the window median is an outlier.")
    plausible_rate_per_s: float | None = Field(
        None, gt=0, description="A raw reading implying a faster change than this (units/s) since the last accepted "
        "value is rejected as implausible. Keep it well above alarms.max_rate_per_s.")
    process_noise_per_s: float | None = Field(
        None, gt=0, description="Kalman process noise: standard deviation of the true value's drift over one second, "
        "in gauge units (it grows with the square root of time); default: 1% of the span.")
    measurement_noise: float | None = Field(
        None, gt=0, description="Kalman measurement noise (std, gauge units), also the floor of the Hampel spread; "
        "default: 0.5% of the span.")
    ema_tau_s: float = Field(1.0, gt=0, description="EMA time constant in seconds.")
    hold_s: float = Field(
        5.0, ge=0, description="After failures, the last valid value is held (quality uncertain) this long before quality turns bad.")
