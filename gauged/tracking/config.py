"""Configuration of per-gauge smoothing: outlier rejection, plausibility and the smoother."""

from __future__ import annotations

from typing import Literal

from pydantic import BaseModel, ConfigDict, Field


class SmoothingConfig(BaseModel):
    """How raw readings of one gauge become the published value (all times are frame times)."""

    model_config = ConfigDict(extra="forbid")

    method: Literal["kalman", "ema", "none"] = Field(
        "kalman", description="Smoother after outlier rejection: 1-D Kalman filter, EMA, or none.")
    hampel_window: int = Field(
        5, ge=1, description="Readings in the median window of the Hampel outlier filter (1 disables it).")
    hampel_k: float = Field(3.0, gt=0, description="A reading further than k scaled MADs from the window median is an outlier.")
    plausible_rate_per_s: float | None = Field(
        None, gt=0, description="A raw reading implying a faster change than this (units/s) is rejected as implausible.")
    process_noise_per_s: float | None = Field(
        None, gt=0, description="Kalman process noise in gauge units per sqrt(second); default: 1% of the span.")
    measurement_noise: float | None = Field(
        None, gt=0, description="Kalman measurement noise (std, gauge units); default: 0.5% of the span.")
    ema_tau_s: float = Field(1.0, gt=0, description="EMA time constant in seconds.")
    hold_s: float = Field(
        5.0, ge=0, description="After failures, the last valid value is held (quality uncertain) this long before quality turns bad.")
