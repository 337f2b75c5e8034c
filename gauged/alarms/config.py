"""Configuration of one gauge's alarm rules (ISA-18.2 style limits with deadband and delays)."""

from __future__ import annotations

from typing import Annotated, Literal

from pydantic import BaseModel, ConfigDict, Field, ValidationError, field_validator, model_validator

from gauged.config.errors import FieldIssues

LimitLevel = Literal["low_low", "low", "high", "high_high"]
LIMIT_LEVELS: tuple[LimitLevel, ...] = ("low_low", "low", "high", "high_high")


class LimitDeadbands(BaseModel):
    """A deadband per limit, in gauge units; a limit left out here has none."""

    model_config = ConfigDict(extra="forbid")

    low_low: float = Field(0.0, ge=0, description="Deadband of the low-low limit.")
    low: float = Field(0.0, ge=0, description="Deadband of the low limit.")
    high: float = Field(0.0, ge=0, description="Deadband of the high limit.")
    high_high: float = Field(0.0, ge=0, description="Deadband of the high-high limit.")


class AlarmsConfig(BaseModel):
    """Alarm limits of one gauge, in the gauge's units. Any limit left out is not checked."""

    model_config = ConfigDict(extra="forbid")

    low_low: float | None = Field(None, description="Low-low limit: value at or below it raises LOLO.")
    low: float | None = Field(None, description="Low limit: value at or below it raises LO.")
    high: float | None = Field(None, description="High limit: value at or above it raises HI.")
    high_high: float | None = Field(None, description="High-high limit: value at or above it raises HIHI.")
    deadband: Annotated[float, Field(ge=0)] | LimitDeadbands = Field(
        0.0, description="Hysteresis in gauge units: an alarm clears only once the value is back past "
        "limit -/+ deadband. One number for every limit, or a mapping {low_low, low, high, high_high}.")
    on_delay_s: float = Field(
        0.0, ge=0, description="The value must stay past the limit this long before the alarm activates.")
    off_delay_s: float = Field(
        0.0, ge=0, description="The value must stay back past limit -/+ deadband this long before the alarm clears.")
    stale_after_s: float = Field(
        10.0, gt=0, description="No valid reading for this long makes the reading stale and raises the stale alarm.")
    max_rate_per_s: float | None = Field(
        None, gt=0, description="Rate-of-change alarm: |d value / dt| above this (gauge units per second).")
    rate_window_s: float = Field(
        2.0, gt=0, description="The rate of change is the smoothed value's change over this window (seconds).")
    failure_ratio: float = Field(
        0.5, gt=0, le=1, description="Reading-failure alarm: ratio of failed frames over failure_window_s "
        "(it clears below half this ratio).")
    failure_window_s: float = Field(30.0, gt=0, description="Window of the reading-failure ratio.")
    failure_min_frames: int = Field(
        5, ge=1, description="The failure ratio is judged only over at least this many frames.")
    shelve_default_s: float = Field(
        3600.0, gt=0, description="How long a shelve lasts when the command gives no duration_s.")
    shelve_max_s: float = Field(
        28800.0, gt=0, description="The longest shelve a command may ask for (ISA-18.2: shelving is always timed).")

    @field_validator("deadband", mode="before")
    @classmethod
    def _deadband_shape(cls, value: object) -> object:
        # Validated here rather than by the union, whose errors would name both alternatives.
        if isinstance(value, (int, float)) and not isinstance(value, bool):
            if value < 0:
                raise ValueError(f"must be >= 0 (gauge units), got {value:g}")
            return float(value)
        if isinstance(value, LimitDeadbands):
            return value
        if isinstance(value, dict):
            try:
                return LimitDeadbands.model_validate(value)
            except ValidationError as exc:
                issues = FieldIssues()
                for err in exc.errors():
                    message = "unknown key (one of low_low, low, high, high_high)" if err["type"] == "extra_forbidden" else err["msg"]
                    issues.add(tuple(err["loc"]), message)
                raise issues from None
        raise ValueError("must be a number >= 0 or a mapping {low_low, low, high, high_high}")

    @model_validator(mode="after")
    def _limits_ordered(self) -> AlarmsConfig:
        issues = FieldIssues()
        given = [(name, value) for name, value in self.limits().items() if value is not None]
        for (lower_name, lower), (upper_name, upper) in zip(given, given[1:]):
            if not upper > lower:
                issues.add((upper_name,), f"must be greater than alarms.{lower_name} ({lower:g})")
        if isinstance(self.deadband, LimitDeadbands):
            for level in LIMIT_LEVELS:
                if getattr(self.deadband, level) > 0 and getattr(self, level) is None:
                    issues.add(("deadband", level), f"alarms.{level} is not set, so it has no deadband")
        if self.shelve_default_s > self.shelve_max_s:
            issues.add(("shelve_default_s",), f"must not exceed alarms.shelve_max_s ({self.shelve_max_s:g})")
        issues.raise_if_any()
        return self

    def limits(self) -> dict[LimitLevel, float | None]:
        """The four limits in order from low-low to high-high (``None`` where not configured)."""
        return {level: getattr(self, level) for level in LIMIT_LEVELS}

    def deadband_of(self, level: LimitLevel) -> float:
        """The deadband of one limit, whichever way ``deadband`` was written."""
        if isinstance(self.deadband, LimitDeadbands):
            return float(getattr(self.deadband, level))
        return float(self.deadband)
