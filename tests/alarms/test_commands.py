from __future__ import annotations

import json
from typing import Any

import pytest
from hypothesis import given
from hypothesis import strategies as st

from gauged.alarms.commands import AlarmCommand, CommandResult, handle_alarm_command, parse_alarm_command
from gauged.alarms.config import AlarmsConfig
from gauged.alarms.gauge_alarms import GaugeAlarms
from gauged.alarms.lifecycle import AlarmState
from gauged.types import FrameOutcome
from gauged.types import Quality, Reading, ScaleInfo

NS = 1_000_000_000
ALICE = {"level": "high", "who": "alice", "why": "checked the pump"}


@pytest.mark.parametrize(
    ("kind", "payload", "expected"),
    [
        ("ack", json.dumps(ALICE).encode(), AlarmCommand("ack", "high", "alice", "checked the pump")),
        ("ack", '{"level": "all", "who": " bob "}', AlarmCommand("ack", "all", "bob")),
        ("shelve", {**ALICE, "duration_s": 600}, AlarmCommand("shelve", "high", "alice", "checked the pump", 600.0)),
        ("shelve", ALICE, AlarmCommand("shelve", "high", "alice", "checked the pump")),
        ("unshelve", {"level": "high", "who": "alice"}, AlarmCommand("unshelve", "high", "alice")),
    ],
)
def test_parse_alarm_command_accepts_well_formed_payloads(kind: str, payload: Any, expected: AlarmCommand) -> None:
    assert parse_alarm_command(kind, payload) == expected


@pytest.mark.parametrize(
    ("kind", "payload", "message"),
    [
        ("silence", ALICE, "unknown command 'silence'"),
        ("ack", b"\xff\xfe", "not UTF-8"),
        ("ack", "{level: high}", "not JSON"),
        ("ack", "[1, 2]", "must be a JSON object"),
        ("ack", {"who": "alice"}, "'level' is required"),
        ("ack", {"level": "high"}, "'who' is required"),
        ("ack", {"level": "high", "who": ""}, "'who' must be a non-empty string"),
        ("ack", {"level": "high", "who": 7}, "'who' must be a non-empty string"),
        ("ack", {"level": "high", "who": "x" * 201}, "longer than 200"),
        ("ack", {**ALICE, "until": 5}, "unknown key(s) 'until'"),
        ("ack", {**ALICE, "duration_s": 60}, "only with shelve"),
        ("shelve", {"level": "high", "who": "alice"}, "'why' is required"),
        ("shelve", {**ALICE, "duration_s": 0}, "'duration_s' must be a number of seconds > 0"),
        ("shelve", {**ALICE, "duration_s": True}, "'duration_s' must be"),
        ("shelve", {**ALICE, "duration_s": "600"}, "'duration_s' must be"),
        ("ack", b"{" + b" " * 5000 + b"}", "larger than 4096 bytes"),
    ],
)
def test_parse_alarm_command_refuses_with_a_reason(kind: str, payload: Any, message: str) -> None:
    result = parse_alarm_command(kind, payload)
    assert isinstance(result, CommandResult) and not result
    assert message in result.message


def alarms_with_high_active() -> GaugeAlarms:
    alarms = GaugeAlarms("boiler", AlarmsConfig(high=8.0, high_high=9.0, shelve_max_s=3600.0))
    reading = Reading("boiler", "cam", 10 * NS, 8.5, 8.5, "bar", Quality.GOOD, 1.0, ScaleInfo(0.0, 10.0, "bar"))
    assert alarms.update(reading, FrameOutcome.ACCEPTED)
    return alarms


@pytest.mark.parametrize(
    ("kind", "payload", "ok", "message", "high_state"),
    [
        ("ack", ALICE, True, "acknowledged high", AlarmState.ACTIVE_ACKNOWLEDGED),
        ("ack", {"level": "all", "who": "alice"}, True, "acknowledged high", AlarmState.ACTIVE_ACKNOWLEDGED),
        ("ack", {"level": "high_high", "who": "alice"}, True, "nothing awaited acknowledgement (high_high: normal)",
         AlarmState.ACTIVE_UNACKNOWLEDGED),
        ("ack", {"level": "low", "who": "alice"}, False, "has no 'low' alarm (alarms: high, high_high, stale, failure",
         AlarmState.ACTIVE_UNACKNOWLEDGED),
        ("shelve", {**ALICE, "duration_s": 600}, True, "shelved high for 600 s", AlarmState.SHELVED),
        ("shelve", ALICE, True, "shelved high for 3600 s", AlarmState.SHELVED),  # shelve_default_s
        ("shelve", {**ALICE, "duration_s": 7200}, False, "exceeds alarms.shelve_max_s (3600)",
         AlarmState.ACTIVE_UNACKNOWLEDGED),
        ("unshelve", {"level": "high", "who": "alice"}, True, "nothing was shelved", AlarmState.ACTIVE_UNACKNOWLEDGED),
    ],
)
def test_handle_alarm_command_applies_or_explains(
        kind: str, payload: dict[str, Any], ok: bool, message: str, high_state: AlarmState) -> None:
    alarms = alarms_with_high_active()
    result = handle_alarm_command(alarms, kind, payload, 20 * NS)
    assert (result.ok, alarms.alarms["high"].state) == (ok, high_state)
    assert message in result.message
    assert all(event.who == "alice" for event in result.events)


def test_handle_alarm_command_shelve_then_expire_reannounces_an_active_alarm() -> None:
    alarms = alarms_with_high_active()
    result = handle_alarm_command(alarms, "shelve", {**ALICE, "duration_s": 60}, 20 * NS)
    [event] = result.events
    assert event.to_dict()["who"] == "alice" and event.to_dict()["why"] == "checked the pump"
    assert alarms.tick(79 * NS) == []
    [expired] = alarms.tick(80 * NS)
    assert (expired.transition.value, expired.state) == ("shelve_expired", AlarmState.ACTIVE_UNACKNOWLEDGED)


def test_handle_alarm_command_unshelve_ends_a_shelve() -> None:
    alarms = alarms_with_high_active()
    handle_alarm_command(alarms, "shelve", {**ALICE, "duration_s": 60}, 20 * NS)
    result = handle_alarm_command(alarms, "unshelve", {"level": "high", "who": "bob", "why": "done"}, 30 * NS)
    assert result and result.to_dict()["events"][0]["state"] == "active_unacknowledged"


@given(st.one_of(st.binary(max_size=300), st.text(max_size=300),
                 st.dictionaries(st.text(max_size=12), st.one_of(st.none(), st.integers(), st.text(max_size=20)),
                                 max_size=5)))
def test_handle_alarm_command_never_raises(payload: Any) -> None:
    alarms = alarms_with_high_active()
    for kind in ("ack", "shelve", "unshelve"):
        result = handle_alarm_command(alarms, kind, payload, 20 * NS)
        assert isinstance(result.to_dict()["message"], str)
