from __future__ import annotations

import doctest

import pytest

import gauged.alarms.condition
from gauged.alarms.condition import DelayedCondition, LimitRule


def test_condition_docstring_examples_run() -> None:
    failed, tried = doctest.testmod(gauged.alarms.condition)
    assert tried > 0 and failed == 0


# (on delay, off delay, [(t, input)], [t at which `active` flips])
DELAY_SCRIPTS = [
    (0, 0, [(0, True), (1, False), (2, True)], [0, 1, 2]),
    (2, 0, [(0, True), (1, True), (2, True), (3, False)], [2, 3]),
    (2, 0, [(0, True), (1, False), (2, True), (3, True), (4, True)], [4]),  # a dip restarts the on-delay
    (0, 3, [(0, True), (1, False), (2, False), (3, True), (4, False), (7, False)], [0, 7]),
    (5, 5, [(0, True), (9, True)], [9]),  # sparse frames: the delay is time, not frame count
]


@pytest.mark.parametrize(("on", "off", "script", "flips"), DELAY_SCRIPTS)
def test_delayed_condition_flips_only_after_delays(
        on: int, off: int, script: list[tuple[int, bool]], flips: list[int]) -> None:
    condition = DelayedCondition(on, off)
    assert [t for t, value in script if condition.observe(value, t)] == flips


def test_delayed_condition_cancel_pending_restarts_the_delay() -> None:
    condition = DelayedCondition(2, 0)
    condition.observe(True, 0)
    condition.cancel_pending()
    assert not condition.observe(True, 2) and condition.observe(True, 4)


# (level, limit, deadband, value, active before, past the limit?)
LIMIT_TABLE = [
    ("high", 8.0, 0.2, 8.0, False, True),
    ("high", 8.0, 0.2, 7.99, False, False),
    ("high", 8.0, 0.2, 7.9, True, True),  # inside the deadband an active alarm stays
    ("high", 8.0, 0.2, 7.8, True, True),  # exactly at limit - deadband: not yet back past it
    ("high", 8.0, 0.2, 7.79, True, False),
    ("high_high", 9.0, 0.0, 8.99, True, False),
    ("low", 2.0, 0.5, 2.0, False, True),
    ("low", 2.0, 0.5, 2.4, True, True),
    ("low", 2.0, 0.5, 2.51, True, False),
    ("low_low", 1.0, 0.1, 1.01, False, False),
]


@pytest.mark.parametrize(("level", "limit", "deadband", "value", "active", "past"), LIMIT_TABLE)
def test_limit_rule_applies_deadband_only_while_active(
        level: str, limit: float, deadband: float, value: float, active: bool, past: bool) -> None:
    assert LimitRule(level, limit, deadband).past(value, active) is past  # type: ignore[arg-type]


def test_limit_rule_messages_name_limit_and_clear_point() -> None:
    rule = LimitRule("low", 2.0, 0.5)
    assert rule.activated_message("tank", 1.5, " bar") == "tank LO: 1.5 bar <= limit 2 bar"
    assert rule.cleared_message("tank", 2.6, " bar") == "tank LO cleared: 2.6 bar back above 2.5 bar"
