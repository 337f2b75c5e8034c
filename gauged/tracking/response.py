"""Measured response of a smoothing config: step response, ramp lag and noise reduction.

Runs the real filter chain (:class:`GaugeSmoother`) on synthetic readings at a fixed frame rate, so
the figures in docs/alarms.md are reproducible and a user can see what their own settings do:

>>> from gauged.tracking.config import SmoothingConfig
>>> figures = characterize(SmoothingConfig(), fps=10.0)
>>> figures.step_90_s <= 1.0 and figures.ramp_lag_s <= 0.5
True
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from gauged.tracking.config import DEFAULT_MEASUREMENT_NOISE_SPAN_FRACTION, SmoothingConfig
from gauged.tracking.gauge_smoother import NS_PER_S, GaugeSmoother
from gauged.types import Quality, RawReading, ScaleInfo

STEP_FROM, STEP_TO = 0.2, 0.8  # fractions of the span
RAMP_RATE_SPAN_PER_S = 0.05  # a needle crossing the dial in 20 s
SETTLE_SPAN_FRACTION = 0.01


@dataclass(frozen=True, slots=True)
class ResponseFigures:
    """Figures of one config at one frame rate; times in seconds, ``noise_ratio`` output/input std."""

    fps: float
    step_first_move_s: float  # step to the first published move (the Hampel window's delay)
    step_90_s: float  # step to 90 % of the step height
    step_settle_s: float  # step to within 1 % of the span, for good
    ramp_rate_per_s: float
    ramp_lag_s: float  # steady-state lag behind a ramp: (ramp value - published value) / rate
    noise_ratio: float  # std of the published value / std of white reader noise


def _run(config: SmoothingConfig, fps: float, span: float, values: np.ndarray) -> np.ndarray:
    smoother = GaugeSmoother("g", "c", config, stale_after_s=1e9, prior_scale=ScaleInfo(0.0, span, None))
    out = np.full(len(values), np.nan)
    for i, value in enumerate(values):
        stamp = int(round(i * NS_PER_S / fps))
        reading = smoother.update(RawReading("g", "c", stamp, float(value), None, 1.0)).reading
        if reading.value is not None and reading.quality in (Quality.GOOD, Quality.UNCERTAIN):
            out[i] = reading.value
        elif i:
            out[i] = out[i - 1]
    return out


def characterize(config: SmoothingConfig, fps: float = 10.0, span: float = 10.0, seed: int = 0) -> ResponseFigures:
    """Measure ``config`` at ``fps`` frames per second on a gauge of ``span`` units."""
    settle_frames = int(30 * fps)
    n = settle_frames * 2
    t = np.arange(n) / fps

    step = np.where(np.arange(n) < settle_frames, STEP_FROM * span, STEP_TO * span)
    out = _run(config, fps, span, step)
    after = out[settle_frames:]
    height = (STEP_TO - STEP_FROM) * span
    moved = np.flatnonzero(after > STEP_FROM * span + 1e-9)
    reached = np.flatnonzero(after >= STEP_FROM * span + 0.9 * height)
    outside = np.flatnonzero(np.abs(after - STEP_TO * span) > SETTLE_SPAN_FRACTION * span)
    first_move = float(moved[0] / fps) if len(moved) else float("inf")
    step_90 = float(reached[0] / fps) if len(reached) else float("inf")
    settle = float((outside[-1] + 1) / fps) if len(outside) else 0.0

    rate = RAMP_RATE_SPAN_PER_S * span
    ramp = 0.1 * span + rate * t
    out = _run(config, fps, span, ramp)
    tail = slice(n - int(5 * fps), n)  # the lag has long reached steady state by then
    ramp_lag = float(np.mean(ramp[tail] - out[tail]) / rate)

    noise_std = (config.measurement_noise or DEFAULT_MEASUREMENT_NOISE_SPAN_FRACTION * span)
    rng = np.random.default_rng(seed)
    noisy = 0.5 * span + rng.normal(0.0, noise_std, n)
    out = _run(config, fps, span, noisy)
    noise_ratio = float(np.std(out[settle_frames:]) / np.std(noisy[settle_frames:]))
    return ResponseFigures(fps, first_move, step_90, settle, rate, ramp_lag, noise_ratio)
