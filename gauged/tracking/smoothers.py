"""The smoothers that follow outlier rejection: a 1-D Kalman filter, an EMA, and none.

All take the time since the previous accepted reading, so an irregular frame rate (dropped frames,
a slow camera) smooths by time, not by frame count. ``weight`` in ``(0, 1]`` is the reader's
confidence: a doubtful reading moves the estimate less.
"""

from __future__ import annotations

import math
from typing import Protocol

MIN_WEIGHT = 0.1  # a reading the reader passed at all still counts for something


class Smoother(Protocol):
    """What the smoothing chain needs of a smoother."""

    value: float

    def reset(self, value: float) -> None:
        """Start over at ``value`` (first reading, or after a dropout)."""

    def update(self, measurement: float, dt_s: float, weight: float = 1.0) -> float:
        """Fold in one accepted measurement taken ``dt_s`` after the previous one; return the estimate."""


class ScalarKalman:
    """A local-level (random-walk) Kalman filter: the true value drifts, the reader adds noise.

    Model: ``x_t = x_{t-dt} + w`` with ``w ~ N(0, q^2 dt)``, measurement ``z = x + v`` with
    ``v ~ N(0, r^2 / weight)``. ``q`` is in gauge units per sqrt(second) (the std of the drift over
    one second), ``r`` in gauge units. Unlike a constant-velocity model it never overshoots a step,
    which matters more next to alarm limits than the small ramp lag it costs:
    at steady state the lag behind a ramp is ``dt (1 - K) / K`` seconds (see :func:`steady_state_gain`).

    >>> kf = ScalarKalman(q=0.1, r=0.05)
    >>> kf.reset(1.0)
    >>> round(kf.update(2.0, dt_s=0.1), 3)
    1.583
    """

    def __init__(self, q: float, r: float) -> None:
        if q <= 0 or r <= 0:
            raise ValueError(f"need q > 0 and r > 0, got q={q}, r={r}")
        self.q = q
        self.r = r
        self.value = 0.0
        self.variance = r * r

    def reset(self, value: float) -> None:
        self.value = float(value)
        self.variance = self.r * self.r

    def update(self, measurement: float, dt_s: float, weight: float = 1.0) -> float:
        self.variance += self.q * self.q * max(dt_s, 0.0)
        noise = self.r * self.r / max(min(weight, 1.0), MIN_WEIGHT)
        gain = self.variance / (self.variance + noise)
        self.value += gain * (measurement - self.value)
        self.variance *= 1.0 - gain
        return self.value


class Ema:
    """Exponential moving average with time constant ``tau_s``: ``alpha = 1 - exp(-dt / tau)``.

    Lags a ramp by ``tau_s`` seconds and reaches 90% of a step after ``2.3 tau_s``.
    """

    def __init__(self, tau_s: float) -> None:
        if tau_s <= 0:
            raise ValueError(f"need tau_s > 0, got {tau_s}")
        self.tau_s = tau_s
        self.value = 0.0

    def reset(self, value: float) -> None:
        self.value = float(value)

    def update(self, measurement: float, dt_s: float, weight: float = 1.0) -> float:
        alpha = (1.0 - math.exp(-max(dt_s, 0.0) / self.tau_s)) * max(min(weight, 1.0), MIN_WEIGHT)
        self.value += alpha * (measurement - self.value)
        return self.value


class Passthrough:
    """No smoothing: the accepted measurement is the value (outlier rejection still applies)."""

    def __init__(self) -> None:
        self.value = 0.0

    def reset(self, value: float) -> None:
        self.value = float(value)

    def update(self, measurement: float, dt_s: float, weight: float = 1.0) -> float:
        self.value = float(measurement)
        return self.value


def steady_state_gain(q: float, r: float, dt_s: float) -> float:
    """Kalman gain of :class:`ScalarKalman` at steady state for a fixed frame interval.

    Solves the scalar Riccati equation ``P = (P + Q)(1 - K)``, ``K = (P + Q) / (P + Q + R)`` with
    ``Q = q^2 dt`` and ``R = r^2``: the prior variance is ``(Q + sqrt(Q^2 + 4 Q R)) / 2``.

    >>> round(steady_state_gain(q=0.1, r=0.05, dt_s=0.1), 3)
    0.463
    """
    process = q * q * dt_s
    noise = r * r
    prior = (process + math.sqrt(process * process + 4.0 * process * noise)) / 2.0
    return prior / (prior + noise)
