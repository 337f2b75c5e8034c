"""Alarm conditions: limits with deadband, and the on/off delays that debounce them.

A limit alarm is a Schmitt trigger followed by a debouncer. While the alarm is clear, the value is
*past the limit* when ``value >= high`` (or ``<= low``); while it is active, the value still counts
as past it until it is back below ``high - deadband`` (above ``low + deadband``). The debouncer then
changes the alarm only after the input has disagreed with it *continuously* for the on-delay (to
activate) or the off-delay (to clear), so a one-frame excursion never changes anything.
"""

from __future__ import annotations

from dataclasses import dataclass

from gauged.alarms.config import LimitLevel

NS_PER_S = 1_000_000_000

LEVEL_LABELS: dict[str, str] = {"low_low": "LOLO", "low": "LO", "high": "HI", "high_high": "HIHI"}


class DelayedCondition:
    """A boolean condition with an on-delay and an off-delay (ISA-18.2 alarm delays), in frame time.

    >>> c = DelayedCondition(on_delay_ns=2, off_delay_ns=0)
    >>> [c.observe(True, t) for t in (0, 1, 2)], c.active
    ([False, False, True], True)
    """

    def __init__(self, on_delay_ns: int, off_delay_ns: int, active: bool = False) -> None:
        self.on_delay_ns = on_delay_ns
        self.off_delay_ns = off_delay_ns
        self.active = active
        self.pending_since_ns: int | None = None  # when the input began to disagree with `active`

    def observe(self, condition: bool, now_ns: int) -> bool:
        """Feed the undelayed condition at ``now_ns``; return True when :attr:`active` changed."""
        if condition == self.active:
            self.pending_since_ns = None
            return False
        if self.pending_since_ns is None:
            self.pending_since_ns = now_ns
        delay = self.off_delay_ns if self.active else self.on_delay_ns
        if now_ns - self.pending_since_ns < delay:
            return False
        self.active = condition
        self.pending_since_ns = None
        return True

    def cancel_pending(self) -> None:
        """Drop a change in progress: without fresh values, a delay cannot be said to have run."""
        self.pending_since_ns = None


@dataclass(frozen=True, slots=True)
class LimitRule:
    """One of the four limits: its level, value and deadband, in gauge units."""

    level: LimitLevel
    limit: float
    deadband: float

    @property
    def is_high(self) -> bool:
        return self.level in ("high", "high_high")

    @property
    def label(self) -> str:
        return LEVEL_LABELS[self.level]

    @property
    def clear_at(self) -> float:
        """The value the reading must get back past before the alarm clears."""
        return self.limit - self.deadband if self.is_high else self.limit + self.deadband

    def past(self, value: float, active: bool) -> bool:
        """Whether ``value`` counts as past the limit, given whether the alarm is active (hysteresis)."""
        threshold = self.clear_at if active else self.limit
        return value >= threshold if self.is_high else value <= threshold

    def activated_message(self, gauge: str, value: float, unit: str) -> str:
        relation = ">=" if self.is_high else "<="
        return f"{gauge} {self.label}: {value:.4g}{unit} {relation} limit {self.limit:g}{unit}"

    def cleared_message(self, gauge: str, value: float, unit: str) -> str:
        side = "below" if self.is_high else "above"
        return f"{gauge} {self.label} cleared: {value:.4g}{unit} back {side} {self.clear_at:g}{unit}"
