"""Configuration of one gauge's alarm rules (ISA-18.2 style limits with deadband and delays)."""

from __future__ import annotations

from pydantic import BaseModel, ConfigDict, Field, model_validator

from gauged.config.errors import FieldIssues


class AlarmsConfig(BaseModel):
    """Alarm limits of one gauge, in the gauge's units. Any limit left out is not checked."""

    model_config = ConfigDict(extra="forbid")

    low_low: float | None = Field(None, description="Low-low limit: value at or below it raises LOLO.")
    low: float | None = Field(None, description="Low limit: value at or below it raises LO.")
    high: float | None = Field(None, description="High limit: value at or above it raises HI.")
    high_high: float | None = Field(None, description="High-high limit: value at or above it raises HIHI.")
    deadband: float = Field(
        0.0, ge=0, description="Hysteresis in gauge units: an alarm clears only once the value is back "
        "past limit -/+ deadband.")
    on_delay_s: float = Field(0.0, ge=0, description="The condition must hold this long before the alarm activates.")
    off_delay_s: float = Field(0.0, ge=0, description="The condition must be gone this long before the alarm clears.")
    stale_after_s: float = Field(
        10.0, gt=0, description="No valid reading for this long makes the reading stale and raises the stale alarm.")
    max_rate_per_s: float | None = Field(
        None, gt=0, description="Rate-of-change alarm: |d value / dt| above this (gauge units per second).")
    failure_ratio: float = Field(
        0.5, gt=0, le=1, description="Reading-failure alarm: ratio of failed frames over failure_window_s.")
    failure_window_s: float = Field(30.0, gt=0, description="Window of the reading-failure ratio.")

    @model_validator(mode="after")
    def _limits_ordered(self) -> AlarmsConfig:
        order = [("low_low", self.low_low), ("low", self.low), ("high", self.high), ("high_high", self.high_high)]
        given = [(name, value) for name, value in order if value is not None]
        issues = FieldIssues()
        for (lower_name, lower), (upper_name, upper) in zip(given, given[1:]):
            if not upper > lower:
                issues.add((upper_name,), f"must be greater than alarms.{lower_name} ({lower:g})")
        issues.raise_if_any()
        return self
