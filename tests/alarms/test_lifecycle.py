from __future__ import annotations

from typing import Any

import pytest

from gauged.alarms.lifecycle import Alarm, AlarmEvent, AlarmState, Transition

N, AU, AA, RU, SH = (AlarmState.NORMAL, AlarmState.ACTIVE_UNACKNOWLEDGED, AlarmState.ACTIVE_ACKNOWLEDGED,
                     AlarmState.RETURNED_UNACKNOWLEDGED, AlarmState.SHELVED)


def act(alarm: Alarm, action: str, t: int) -> AlarmEvent | None:
    if action == "on":
        return alarm.set_active(True, t, 9.0, "on")
    if action == "off":
        return alarm.set_active(False, t, 7.0, "off")
    if action == "ack":
        return alarm.acknowledge("alice", "seen", t)
    if action == "shelve":
        return alarm.shelve("bob", "sensor swap", t, until_ns=t + 100)
    if action == "unshelve":
        return alarm.unshelve("bob", "done", t)
    if action == "expire":
        return alarm.expire(t)
    raise AssertionError(action)


# ISA-18.2 fig. 8: actions in order -> (transition or None) per action, and the final state.
LIFECYCLE_SCRIPTS = [
    (["on"], ["activated"], AU),
    (["on", "ack"], ["activated", "acknowledged"], AA),
    (["on", "off"], ["activated", "cleared"], RU),
    (["on", "off", "ack"], ["activated", "cleared", "acknowledged"], N),
    (["on", "ack", "off"], ["activated", "acknowledged", "cleared"], N),
    (["on", "off", "on"], ["activated", "cleared", "activated"], AU),
    (["on", "on", "ack", "ack"], ["activated", None, "acknowledged", None], AA),
    (["ack", "off"], [None, None], N),
    (["shelve", "on", "off", "on"], ["shelved", None, None, None], SH),  # silent while shelved
    (["shelve", "on", "unshelve"], ["shelved", None, "unshelved"], AU),  # re-announced when it ends
    (["on", "ack", "shelve", "off", "unshelve"], ["activated", "acknowledged", "shelved", None, "unshelved"], N),
    (["shelve", "shelve"], ["shelved", None], SH),  # a re-shelve moves the end, no state change
    (["unshelve"], [None], N),
    (["shelve", "ack"], ["shelved", None], SH),
]


@pytest.mark.parametrize(("actions", "transitions", "final"), LIFECYCLE_SCRIPTS)
def test_alarm_lifecycle_follows_isa_18_2(actions: list[str], transitions: list[str | None], final: AlarmState) -> None:
    alarm = Alarm("g", "high", 8.0)
    events = [act(alarm, action, t) for t, action in enumerate(actions)]
    assert [None if e is None else e.transition.value for e in events] == transitions
    assert alarm.state is final
    for event in events:
        if event is not None:
            assert event.state is not event.previous  # an event is always a state change


def test_alarm_shelve_expires_at_its_time_only() -> None:
    alarm = Alarm("g", "high", 8.0)
    alarm.set_active(True, 0, 9.0, "on")
    alarm.shelve("bob", "maintenance", 10, until_ns=70)
    assert alarm.expire(69) is None
    event = alarm.expire(70)
    assert event is not None and (event.transition, event.state) == (Transition.SHELVE_EXPIRED, AU)
    assert alarm.status().shelved_until_ns is None


def test_alarm_event_to_dict_matches_the_contract() -> None:
    alarm = Alarm("boiler", "high", 8.0)
    alarm.set_active(True, 5, 8.4, "boiler HI: 8.4 bar >= limit 8 bar")
    event = alarm.acknowledge("alice", "on it", 7)
    assert event is not None
    assert event.to_dict() == {
        "gauge": "boiler", "stamp_ns": 7, "level": "high", "state": "active_acknowledged", "value": 8.4,
        "limit": 8.0, "message": "boiler high acknowledged by alice: on it", "previous": "active_unacknowledged",
        "transition": "acknowledged", "who": "alice", "why": "on it",
    }
    activation = Alarm("boiler", "high", 8.0).set_active(True, 5, 8.4, "m")
    assert activation is not None and "who" not in activation.to_dict() and "why" not in activation.to_dict()


def test_alarm_snapshot_round_trips() -> None:
    alarm = Alarm("g", "high", 8.0)
    alarm.set_active(True, 1, 8.5, "on")
    alarm.shelve("bob", "swap", 2, until_ns=500)
    copy = Alarm("g", "high", 8.0)
    copy.restore(alarm.snapshot())
    assert copy.status() == alarm.status()


@pytest.mark.parametrize(
    ("saved", "problem"),
    [
        ({"state": "flashing", "active": True}, "flashing"),
        ({"active": True}, "state"),
        ({"state": "active_acknowledged", "active": False}, "contradicts"),
        ({"state": "normal", "active": "yes"}, "true or false"),
        ({"state": "shelved", "active": False}, "shelved_until_ns"),
        ({"state": "normal", "active": False, "since_ns": 1.5}, "expected a finite int"),
        ({"state": "normal", "active": False, "value": float("inf")}, "expected a finite float"),
    ],
)
def test_alarm_restore_refuses_malformed_state(saved: dict[str, Any], problem: str) -> None:
    alarm = Alarm("g", "high", 8.0)
    with pytest.raises(ValueError, match=problem):
        alarm.restore(saved)
    assert alarm.state is N and not alarm.active
