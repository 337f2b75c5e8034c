"""The filter chain of one gauge: raw readings in, published readings with a quality out.

Chain per frame (all times are frame stamps, never the wall clock):

1. a reading without a value (a stage failure) or with a non-finite one is *failed*;
2. the causal Hampel test rejects *outliers* against the last ``hampel_window`` raw values;
3. the plausibility check rejects a value that would mean a faster change than
   ``plausible_rate_per_s`` since the last accepted value (the allowance grows with the time since,
   so a real jump is taken once enough time has passed, as water-meter readers do);
4. an accepted value updates the smoother (Kalman, EMA or none).

Quality (see docs/alarms.md): ``good`` for an accepted value once the window has enough readings;
``uncertain`` while recovering, or when a frame is rejected or fails and the last estimate is held
(for at most ``hold_s``); ``bad`` (value null) when frames keep failing; ``stale`` (value null) when
there has been no valid reading for ``stale_after_s``, also detected by :meth:`GaugeSmoother.tick`
when no frame arrives at all. A failed frame never zeroes the value.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from gauged.tracking.config import (
    DEFAULT_MEASUREMENT_NOISE_SPAN_FRACTION,
    DEFAULT_PROCESS_NOISE_SPAN_FRACTION,
    SmoothingConfig,
)
from gauged.tracking.hampel import HampelWindow
from gauged.tracking.smoothers import Ema, Passthrough, ScalarKalman, Smoother
from gauged.types import FrameOutcome, Quality, RawReading, Reading, ScaleInfo

NS_PER_S = 1_000_000_000
FALLBACK_SPAN = 1.0  # used only until a scale is known; the Kalman gain depends on q/r alone
PLAUSIBLE_NOISE_SIGMAS = 3.0  # jitter allowed on top of plausible_rate_per_s * dt

# Reason tokens of a published reading (machine-readable, stable).
REASON_RECOVERING = "recovering"
REASON_OUTLIER = "outlier"
REASON_IMPLAUSIBLE = "implausible_rate"
REASON_HELD = "held"
REASON_NO_VALID = "no_valid_reading"


@dataclass(frozen=True, slots=True)
class Smoothed:
    """A published reading and how the frame behind it was used."""

    reading: Reading
    outcome: FrameOutcome


def _failure_reason(raw: RawReading) -> str:
    if raw.failure is not None:
        return f"failed:{raw.failure.stage}/{raw.failure.reason}"
    return "failed:no_value" if raw.value is None else "failed:not_finite"


class GaugeSmoother:
    """Smoothing and quality of one gauge.

    ``prior_scale`` is the configured scale (its span sets the default noise levels until the
    reader supplies one); ``stale_after_s`` comes from the gauge's alarm config so that the stale
    quality and the stale alarm agree.
    """

    def __init__(self, gauge: str, camera: str, config: SmoothingConfig, stale_after_s: float,
                 prior_scale: ScaleInfo | None = None) -> None:
        self.gauge = gauge
        self.camera = camera
        self.config = config
        self.stale_after_ns = int(stale_after_s * NS_PER_S)
        self.hold_ns = int(config.hold_s * NS_PER_S)
        self.recover_samples = config.hampel_window // 2 + 1
        self._scale = prior_scale or ScaleInfo(None, None, None)
        self._hampel = HampelWindow(config.hampel_window, config.hampel_k, floor=0.0)
        self._smoother: Smoother = self._make_smoother()
        self._span: float | None = None
        self._set_span(self._scale_span(self._scale) or FALLBACK_SPAN)
        self._started_ns: int | None = None
        self._last_frame_ns: int | None = None
        self._clear_track()
        self.last_good: tuple[float, int] | None = None  # (value, stamp_ns) of the last good reading

    # --- noise levels -------------------------------------------------------------------------

    @staticmethod
    def _scale_span(scale: ScaleInfo) -> float | None:
        if scale.min is None or scale.max is None or not scale.max > scale.min:
            return None
        return float(scale.max - scale.min)

    def _make_smoother(self) -> Smoother:
        if self.config.method == "kalman":
            return ScalarKalman(q=1.0, r=1.0)  # real noise levels are set by _set_span
        if self.config.method == "ema":
            return Ema(self.config.ema_tau_s)
        return Passthrough()

    def _set_span(self, span: float) -> None:
        if span == self._span:
            return
        self._span = span
        self.measurement_noise = self.config.measurement_noise or DEFAULT_MEASUREMENT_NOISE_SPAN_FRACTION * span
        self.process_noise = self.config.process_noise_per_s or DEFAULT_PROCESS_NOISE_SPAN_FRACTION * span
        self._hampel.floor = self.measurement_noise
        if isinstance(self._smoother, ScalarKalman):
            self._smoother.q = self.process_noise
            self._smoother.r = self.measurement_noise

    # --- state --------------------------------------------------------------------------------

    def _clear_track(self) -> None:
        """Forget the current track (start, dropout, time going back); keeps scale and last_good."""
        self._hampel.reset()
        self._accepted = 0  # accepted readings since the track began
        self._last_accepted_ns: int | None = None
        self._held: float | None = None  # the estimate a failed frame may hold
        self._held_confidence = 0.0
        self._stale = False

    def reset(self, now_ns: int) -> None:
        """Start a new track at ``now_ns``: the facade calls this when frame time goes backwards."""
        self._clear_track()
        self._started_ns = now_ns
        self._last_frame_ns = None

    def restore_last_good(self, value: float, stamp_ns: int) -> None:
        """Seed the held value and the time of the last valid reading from saved state."""
        self.last_good = (float(value), int(stamp_ns))
        self._held = float(value)
        self._held_confidence = 0.5  # nothing is known about it but that it was good once
        self._last_accepted_ns = int(stamp_ns)

    @property
    def last_frame_ns(self) -> int | None:
        """Stamp of the last frame seen, or None before the first (or after :meth:`reset`)."""
        return self._last_frame_ns

    @property
    def is_stale(self) -> bool:
        return self._stale

    def _note_time(self, now_ns: int) -> None:
        if self._started_ns is None:
            self._started_ns = now_ns

    def _stale_age_ns(self, now_ns: int) -> int:
        # A restored last reading older than this run does not make the run start stale: the
        # daemon had no chance yet, and a stale alarm at every restart would teach operators to ignore it.
        assert self._started_ns is not None
        since = self._started_ns if self._last_accepted_ns is None else max(self._last_accepted_ns, self._started_ns)
        return now_ns - since

    def _enter_stale(self) -> None:
        self._clear_track()
        self._stale = True

    # --- the chain ----------------------------------------------------------------------------

    def _scale_of(self, raw: RawReading | None, locked: bool) -> ScaleInfo:
        if raw is not None and raw.scale is not None:
            model = raw.scale
            if model.max_value > model.min_value:
                self._set_span(float(model.max_value - model.min_value))
            self._scale = ScaleInfo(model.min_value, model.max_value, model.unit or raw.unit or self._scale.unit, locked)
        elif self._scale.locked != locked:
            self._scale = ScaleInfo(self._scale.min, self._scale.max, self._scale.unit, locked)
        return self._scale

    def _implausible(self, value: float, now_ns: int) -> bool:
        rate = self.config.plausible_rate_per_s
        if rate is None or self._accepted < self.recover_samples or self._last_accepted_ns is None:
            return False
        dt_s = (now_ns - self._last_accepted_ns) / NS_PER_S
        allowed = rate * dt_s + PLAUSIBLE_NOISE_SIGMAS * self.measurement_noise
        return abs(value - self._smoother.value) > allowed

    def update(self, raw: RawReading, scale_locked: bool = False) -> Smoothed:
        """Run one raw reading through the chain. ``raw.stamp_ns`` must not go backwards (see :meth:`reset`)."""
        now = raw.stamp_ns
        self._note_time(now)
        self._last_frame_ns = now
        scale = self._scale_of(raw, scale_locked)
        value = raw.value
        if value is None or not math.isfinite(value):
            return self._not_accepted(raw, scale, FrameOutcome.FAILED, _failure_reason(raw))
        verdict = self._hampel.push(value)
        if verdict.outlier:
            return self._not_accepted(raw, scale, FrameOutcome.REJECTED, REASON_OUTLIER)
        if self._implausible(value, now):
            return self._not_accepted(raw, scale, FrameOutcome.REJECTED, REASON_IMPLAUSIBLE)
        return self._accept(raw, scale, value)

    def _accept(self, raw: RawReading, scale: ScaleInfo, value: float) -> Smoothed:
        now = raw.stamp_ns
        confidence = min(max(raw.confidence, 0.0), 1.0)
        if self._accepted < self.recover_samples:
            # Recovering: the estimate is the window median, so one wild first reading cannot seed it.
            self._smoother.reset(self._hampel.median())
            self._accepted += 1
        else:
            dt_s = (now - self._last_accepted_ns) / NS_PER_S if self._last_accepted_ns is not None else 0.0
            self._smoother.update(value, dt_s, weight=confidence)
        self._last_accepted_ns = now
        self._stale = False
        estimate = float(self._smoother.value)
        self._held, self._held_confidence = estimate, confidence
        if self._accepted >= self.recover_samples:
            self.last_good = (estimate, now)
            reading = self._reading(now, estimate, raw, scale, Quality.GOOD, confidence, ())
        else:
            partial = confidence * self._accepted / self.recover_samples
            reading = self._reading(now, estimate, raw, scale, Quality.UNCERTAIN, partial, (REASON_RECOVERING,))
        return Smoothed(reading, FrameOutcome.ACCEPTED)

    def _not_accepted(self, raw: RawReading, scale: ScaleInfo, outcome: FrameOutcome, cause: str) -> Smoothed:
        now = raw.stamp_ns
        if self._stale or self._stale_age_ns(now) >= self.stale_after_ns:
            if not self._stale:
                self._enter_stale()
            reading = self._reading(now, None, raw, scale, Quality.STALE, 0.0, (cause, REASON_NO_VALID))
        else:
            held_for = now - self._last_accepted_ns if self._last_accepted_ns is not None else None
            if self._held is not None and held_for is not None and held_for < self.hold_ns:
                confidence = self._held_confidence * (1.0 - held_for / self.hold_ns)
                reading = self._reading(now, self._held, raw, scale, Quality.UNCERTAIN, confidence, (cause, REASON_HELD))
            else:
                reading = self._reading(now, None, raw, scale, Quality.BAD, 0.0, (cause,))
        return Smoothed(reading, outcome)

    def tick(self, now_ns: int) -> Reading | None:
        """Detect staleness without frames: a ``stale`` reading when it begins, else ``None``."""
        self._note_time(now_ns)
        if self._stale or (self._last_frame_ns is not None and now_ns < self._last_frame_ns):
            return None
        if self._stale_age_ns(now_ns) < self.stale_after_ns:
            return None
        self._enter_stale()
        return self._reading(now_ns, None, None, self._scale, Quality.STALE, 0.0, (REASON_NO_VALID,))

    def _reading(self, stamp_ns: int, value: float | None, raw: RawReading | None, scale: ScaleInfo,
                 quality: Quality, confidence: float, reasons: tuple[str, ...]) -> Reading:
        return Reading(
            gauge=self.gauge,
            camera=self.camera if raw is None else raw.camera,
            stamp_ns=stamp_ns,
            value=value,
            raw_value=raw.value if raw is not None and raw.value is not None and math.isfinite(raw.value) else None,
            unit=(raw.unit if raw is not None and raw.unit else None) or scale.unit,
            quality=quality,
            confidence=float(confidence),
            scale=scale,
            failure=None if raw is None else raw.failure,
            reasons=reasons,
        )
