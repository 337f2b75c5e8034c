from __future__ import annotations

import pytest

from gauged.alarms.config import AlarmsConfig, LimitDeadbands
from gauged.config.errors import ConfigError
from gauged.config.loader import parse_config

HEADER = "cameras: [{id: c, source: {type: zenoh, key: a}}]\ngauges:\n  - id: g\n    camera: c\n"


def alarms_yaml(body: str) -> str:
    return HEADER + f"    alarms: {body}\n"


@pytest.mark.parametrize(
    ("body", "path", "message"),
    [
        ("{deadband: -1}", "gauges[0].alarms.deadband", "must be >= 0"),
        ("{deadband: [1]}", "gauges[0].alarms.deadband", "a number >= 0 or a mapping"),
        ("{high: 3, deadband: {hi: 0.1}}", "gauges[0].alarms.deadband.hi", "unknown key"),
        ("{high: 3, deadband: {high: -0.1}}", "gauges[0].alarms.deadband.high", "greater than or equal to 0"),
        ("{high: 3, deadband: {low: 0.1}}", "gauges[0].alarms.deadband.low", "alarms.low is not set"),
        ("{low: 5, high: 3}", "gauges[0].alarms.high", "must be greater than alarms.low (5)"),
        ("{shelve_default_s: 100, shelve_max_s: 50}", "gauges[0].alarms.shelve_default_s", "must not exceed"),
        ("{failure_min_frames: 0}", "gauges[0].alarms.failure_min_frames", "greater than or equal to 1"),
    ],
)
def test_alarms_config_errors_name_the_field(body: str, path: str, message: str) -> None:
    with pytest.raises(ConfigError) as caught:
        parse_config(alarms_yaml(body))
    issues = [(str(issue).split(" ")[1].rstrip(":"), issue.message) for issue in caught.value.issues]
    assert any(p == path and message in m for p, m in issues), issues


@pytest.mark.parametrize(
    ("deadband", "expected"),
    [
        (0.25, {"low_low": 0.25, "low": 0.25, "high": 0.25, "high_high": 0.25}),
        ({"high": 0.5}, {"low_low": 0.0, "low": 0.0, "high": 0.5, "high_high": 0.0}),
    ],
)
def test_alarms_config_deadband_of_each_limit(deadband: object, expected: dict[str, float]) -> None:
    config = AlarmsConfig(low_low=1.0, low=2.0, high=8.0, high_high=9.0, deadband=deadband)  # type: ignore[arg-type]
    assert {level: config.deadband_of(level) for level in expected} == expected  # type: ignore[arg-type]


def test_alarms_config_defaults_document_every_field() -> None:
    for model in (AlarmsConfig, LimitDeadbands):
        for name, field in model.model_fields.items():
            assert field.description, f"{model.__name__}.{name} has no description"
            assert not field.is_required(), f"{model.__name__}.{name} has no default"
