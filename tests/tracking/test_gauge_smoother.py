from __future__ import annotations

import math

import pytest
from hypothesis import given
from hypothesis import strategies as st

from gauged.tracking.config import SmoothingConfig
from gauged.tracking.gauge_smoother import GaugeSmoother
from gauged.types import FrameOutcome
from gauged.types import Ellipse, Quality, RawReading, ScaleInfo, ScaleModel, StageFailure

NS = 1_000_000_000
FAIL = StageFailure("needle", "no_line", "no needle pixels")
G, U, B, S = Quality.GOOD, Quality.UNCERTAIN, Quality.BAD, Quality.STALE


def raw(t_s: float, value: float | None, confidence: float = 1.0, scale: ScaleModel | None = None) -> RawReading:
    return RawReading("g", "cam", round(t_s * NS), value, "bar", confidence, scale, None if value is not None else FAIL)


def smoother(stale_after_s: float = 3.0, **overrides: object) -> GaugeSmoother:
    config = SmoothingConfig(**{"method": "none", "hold_s": 1.0, **overrides})
    return GaugeSmoother("g", "cam", config, stale_after_s, ScaleInfo(0.0, 10.0, "bar"))


# Script rows: (time s, raw value or None for a stage failure, quality, published value, a reason or "").
QUALITY_SCRIPT = [
    (0.0, 5.0, U, 5.0, "recovering"),
    (0.1, 5.0, U, 5.0, "recovering"),
    (0.2, 5.0, G, 5.0, ""),
    (0.3, None, U, 5.0, "held"),  # one failed frame: the value is held, never zeroed
    (1.1, None, U, 5.0, "failed:needle/no_line"),
    (1.2, None, B, None, "failed:needle/no_line"),  # hold_s = 1 s since the last valid reading
    (3.1, None, B, None, ""),
    (3.2, None, S, None, "no_valid_reading"),  # stale_after_s = 3 s since the last valid reading
    (3.3, None, S, None, ""),
    (3.4, 6.0, U, 6.0, "recovering"),
    (3.5, 6.0, U, 6.0, "recovering"),
    (3.6, 6.0, G, 6.0, ""),
    (3.7, 9.5, U, 6.0, "outlier"),  # a one-frame spike is rejected and the value held
    (3.8, 6.0, G, 6.0, ""),
]


def test_gauge_smoother_quality_follows_script() -> None:
    chain = smoother()
    for t, value, quality, published, reason in QUALITY_SCRIPT:
        reading = chain.update(raw(t, value)).reading
        assert (reading.quality, reading.value) == (quality, published), f"t={t}"
        assert not reason or reason in reading.reasons, f"t={t}: {reading.reasons}"
        assert reading.raw_value == value


def test_gauge_smoother_tick_detects_stale_once_without_frames() -> None:
    chain = smoother()
    for t in (0.0, 0.1, 0.2):
        chain.update(raw(t, 5.0))
    assert chain.tick(round(2.0 * NS)) is None
    stale = chain.tick(round(3.2 * NS))
    assert stale is not None and (stale.quality, stale.value, stale.stamp_ns) == (S, None, round(3.2 * NS))
    assert stale.scale == ScaleInfo(0.0, 10.0, "bar") and stale.unit == "bar" and stale.confidence == 0.0
    assert chain.tick(round(9.0 * NS)) is None  # already stale: reported once
    assert chain.update(raw(9.1, None)).reading.quality is S


def test_gauge_smoother_tick_without_any_frame_goes_stale_after_start() -> None:
    chain = smoother()
    assert chain.tick(100 * NS) is None  # the first tick starts the clock
    reading = chain.tick(103 * NS)
    assert reading is not None and reading.quality is S


def test_gauge_smoother_ignores_tick_behind_the_last_frame() -> None:
    chain = smoother()
    chain.update(raw(10.0, 5.0))
    assert chain.tick(0) is None


def test_gauge_smoother_implausible_jump_is_held_until_time_allows_it() -> None:
    chain = smoother(stale_after_s=10.0, hampel_window=1, plausible_rate_per_s=1.0, hold_s=5.0)
    assert chain.update(raw(0.0, 5.0)).reading.quality is G  # window 1: nothing to recover
    jump = chain.update(raw(0.1, 9.0))
    assert (jump.outcome, jump.reading.value) == (FrameOutcome.REJECTED, 5.0)
    assert "implausible_rate" in jump.reading.reasons
    # 4 units at 1 unit/s (+3 sigma of noise, 0.15) is plausible after 3.85 s.
    assert chain.update(raw(3.8, 9.0)).outcome is FrameOutcome.REJECTED
    late = chain.update(raw(3.9, 9.0))
    assert (late.outcome, late.reading.quality, late.reading.value) == (FrameOutcome.ACCEPTED, G, 9.0)


@pytest.mark.parametrize(
    ("value", "reason"), [(math.nan, "failed:not_finite"), (math.inf, "failed:not_finite"), (None, "failed:needle/no_line")])
def test_gauge_smoother_unusable_values_fail_without_zeroing(value: float | None, reason: str) -> None:
    chain = smoother()
    for t in (0.0, 0.1, 0.2):
        chain.update(raw(t, 5.0))
    bad = RawReading("g", "cam", round(0.3 * NS), value, "bar", 1.0, None, FAIL if value is None else None)
    result = chain.update(bad)
    assert result.outcome is FrameOutcome.FAILED and reason in result.reading.reasons
    assert (result.reading.value, result.reading.raw_value) == (5.0, None)


def _scale(lo: float, hi: float) -> ScaleModel:
    return ScaleModel(Ellipse(0.0, 0.0, 1.0, 1.0, 0.0), slope=1.0, intercept=0.0, zero_angle=0.0,
                      min_value=lo, max_value=hi, unit="psi")


@pytest.mark.parametrize(
    ("prior", "reader_scale", "measurement_noise", "process_noise"),
    [
        (ScaleInfo(0.0, 10.0, "bar"), None, 0.05, 0.1),
        (ScaleInfo(0.0, 10.0, "bar"), _scale(0.0, 600.0), 3.0, 6.0),  # the reader's scale wins
        (None, None, 0.005, 0.01),  # no span known yet: 1 unit
    ],
)
def test_gauge_smoother_noise_defaults_follow_the_span(
        prior: ScaleInfo | None, reader_scale: ScaleModel | None, measurement_noise: float, process_noise: float) -> None:
    chain = GaugeSmoother("g", "cam", SmoothingConfig(), 10.0, prior)
    chain.update(raw(0.0, 5.0, scale=reader_scale))
    assert (chain.measurement_noise, chain.process_noise) == pytest.approx((measurement_noise, process_noise))


def test_gauge_smoother_configured_noise_overrides_the_span() -> None:
    chain = GaugeSmoother("g", "cam", SmoothingConfig(measurement_noise=0.2, process_noise_per_s=0.7), 10.0,
                          ScaleInfo(0.0, 10.0, None))
    assert (chain.measurement_noise, chain.process_noise) == (0.2, 0.7)


def test_gauge_smoother_reports_reader_scale_and_lock() -> None:
    chain = smoother()
    reading = chain.update(raw(0.0, 5.0, scale=_scale(0.0, 16.0)), scale_locked=True).reading
    assert reading.scale == ScaleInfo(0.0, 16.0, "psi", locked=True)
    assert reading.to_dict()["scale"] == {"min": 0.0, "max": 16.0, "unit": "psi", "locked": True}


def test_gauge_smoother_recovery_starts_from_the_window_median() -> None:
    chain = smoother(method="kalman")
    values = [9.0, 5.0, 5.0]  # a wild first reading must not seed the estimate
    readings = [chain.update(raw(0.1 * i, v)).reading for i, v in enumerate(values)]
    assert readings[-1].quality is G and readings[-1].value == 5.0


def test_gauge_smoother_confidence_rises_while_recovering_and_decays_while_held() -> None:
    chain = smoother()
    recovering = [chain.update(raw(0.1 * i, 5.0, confidence=0.9)).reading.confidence for i in range(3)]
    assert recovering == pytest.approx([0.3, 0.6, 0.9])
    held = [chain.update(raw(t, None)).reading.confidence for t in (0.3, 0.7)]
    assert 0.9 > held[0] > held[1] > 0.0


script_steps = st.lists(
    st.tuples(st.floats(0.0, 2.0), st.one_of(st.none(), st.floats(1.0, 10.0))), min_size=1, max_size=60)


@given(script_steps)
def test_gauge_smoother_never_invents_values(steps: list[tuple[float, float | None]]) -> None:
    # Whatever the mix of failures, gaps and values, a published value is one the chain could have
    # read (within the readings' range), it is null exactly when the quality is bad or stale, and a
    # lone failure right after a good reading keeps that reading's value.
    chain = GaugeSmoother("g", "cam", SmoothingConfig(), 3.0, ScaleInfo(0.0, 10.0, "bar"))
    t = 0.0
    previous = None
    for gap, value in steps:
        t += gap
        reading = chain.update(raw(t, value)).reading
        assert (reading.value is None) == (reading.quality in (B, S))
        if reading.value is not None:
            assert 1.0 - 1e-9 <= reading.value <= 10.0 + 1e-9
        if value is None and previous is not None and previous.quality is G and gap < 1.0:
            assert reading.value == previous.value
        previous = reading
