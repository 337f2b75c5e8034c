"""Zenoh sink over real sessions on loopback: puts, queryable, liveliness token, alarm commands."""

from __future__ import annotations

import json
import time

import pytest
import zenoh

from gauged.sinks.zenoh_sink import ZenohSink

PREFIX = "gauged/test"


def wait_for(predicate, timeout: float = 5.0) -> bool:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if predicate():
            return True
        time.sleep(0.02)
    return predicate()


def alarm(gauge: str, level: str, state: str, stamp_ns: int = 1_700_000_000_000_000_000) -> dict:
    return {"gauge": gauge, "stamp_ns": stamp_ns, "level": level, "state": state, "value": 9.1, "limit": 8.0,
            "message": f"{gauge} {level} {state}"}


def get(session: zenoh.Session, selector: str, **kw) -> dict[str, object]:
    """Replies of a get as {key: decoded JSON}; errors under "error"."""
    out: dict[str, object] = {}
    for reply in session.get(selector, timeout=3.0, **kw):
        if reply.ok is not None:
            assert str(reply.ok.encoding) == "application/json"
            out[str(reply.ok.key_expr)] = json.loads(reply.ok.payload.to_bytes())
        else:
            out["error"] = json.loads(reply.err.payload.to_bytes())
    return out


@pytest.fixture
def sink_of(zenoh_pair):
    daemon, peer = zenoh_pair
    made: list[ZenohSink] = []

    def make(**kw) -> tuple[ZenohSink, zenoh.Session]:
        sink = ZenohSink(daemon, PREFIX, "node1", **kw)
        made.append(sink)
        time.sleep(0.3)  # declarations reach the peer
        return sink, peer

    yield make
    for sink in made:
        sink.close()


def test_readings_and_alarms_are_put_as_json(sink_of, reading):
    sink, peer = sink_of()
    got = []
    sub = peer.declare_subscriber(f"{PREFIX}/**", lambda s: got.append(
        (str(s.key_expr), str(s.encoding), json.loads(s.payload.to_bytes()))))
    time.sleep(0.3)
    sink.publish_reading(reading(0))
    event = alarm("boiler-pressure", "high", "active_unacknowledged")
    sink.publish_alarm(event)
    assert wait_for(lambda: len(got) == 2)
    sub.undeclare()
    assert got[0] == (f"{PREFIX}/boiler-pressure/reading", "application/json", reading(0).to_dict())
    assert got[1] == (f"{PREFIX}/boiler-pressure/alarm", "application/json", event)


def test_nan_values_are_published_as_null(sink_of, reading):
    sink, peer = sink_of()
    sink.publish_reading(reading(0, value=float("nan")))
    assert get(peer, f"{PREFIX}/boiler-pressure/reading")[f"{PREFIX}/boiler-pressure/reading"]["value"] is None


def test_queryable_answers_latest_reading_and_alarm_state_per_gauge(sink_of, reading):
    sink, peer = sink_of()
    sink.publish_reading(reading(0, gauge="a"))
    sink.publish_reading(reading(1, gauge="a", value=5.5))
    sink.publish_reading(reading(2, gauge="b"))
    sink.publish_alarm(alarm("a", "high", "active_unacknowledged", 10))
    sink.publish_alarm(alarm("a", "high_high", "active_unacknowledged", 11))
    sink.publish_alarm(alarm("a", "high_high", "normal", 12))
    everything = get(peer, f"{PREFIX}/**")
    assert set(everything) == {f"{PREFIX}/{g}/{k}" for g in "ab" for k in ("reading", "alarm")}
    assert everything[f"{PREFIX}/a/reading"] == reading(1, gauge="a", value=5.5).to_dict()
    state = everything[f"{PREFIX}/a/alarm"]
    assert state["active"] == ["high"] and state["stamp_ns"] == 12
    assert state["levels"]["high_high"]["state"] == "normal"
    assert everything[f"{PREFIX}/b/alarm"] == {"gauge": "b", "stamp_ns": None, "active": [], "levels": {}}
    assert set(get(peer, f"{PREFIX}/*/reading")) == {f"{PREFIX}/a/reading", f"{PREFIX}/b/reading"}
    assert set(get(peer, f"{PREFIX}/b/**")) == {f"{PREFIX}/b/reading", f"{PREFIX}/b/alarm"}


def test_liveliness_token_is_visible_while_open_and_gone_after_close(zenoh_pair):
    daemon, peer = zenoh_pair
    changes = []
    watcher = peer.liveliness().declare_subscriber(f"{PREFIX}/@alive/*", lambda s: changes.append(
        (str(s.key_expr), s.kind)))
    sink = ZenohSink(daemon, PREFIX, "node1")

    def alive() -> list[str]:
        return [str(r.ok.key_expr) for r in peer.liveliness().get(f"{PREFIX}/@alive/*", timeout=1.0) if r.ok]

    assert wait_for(lambda: alive() == [f"{PREFIX}/@alive/node1"])
    sink.close()
    assert wait_for(lambda: alive() == [])
    assert wait_for(lambda: len(changes) == 2)
    watcher.undeclare()
    token = f"{PREFIX}/@alive/node1"
    assert changes == [(token, zenoh.SampleKind.PUT), (token, zenoh.SampleKind.DELETE)]


def test_alarm_commands_by_get_and_put_reach_the_app(sink_of, reading):
    calls = []

    def on_command(gauge: str, command: str, payload: bytes) -> dict:
        calls.append((gauge, command, payload))
        if gauge == "unknown":
            raise KeyError(gauge)
        return {"gauge": gauge, "command": command, "ok": True}

    sink, peer = sink_of(on_command=on_command)
    sink.publish_reading(reading(0, gauge="a"))
    answer = get(peer, f"{PREFIX}/a/alarm/ack", payload=b'{"user": "op1"}')
    assert answer == {f"{PREFIX}/a/alarm/ack": {"gauge": "a", "command": "ack", "ok": True}}
    peer.put(f"{PREFIX}/a/alarm/shelve", b'{"for_s": 600}')
    assert wait_for(lambda: len(calls) == 2)
    assert calls == [("a", "ack", b'{"user": "op1"}'), ("a", "shelve", b'{"for_s": 600}')]
    assert get(peer, f"{PREFIX}/a/alarm/unshelve")[f"{PREFIX}/a/alarm/unshelve"]["command"] == "unshelve"
    assert "KeyError" in get(peer, f"{PREFIX}/unknown/alarm/ack")["error"]["error"]
    get(peer, f"{PREFIX}/**")
    get(peer, f"{PREFIX}/*/alarm/ack")
    assert len(calls) == 4  # wildcard selectors never run a command


def test_queryable_uses_the_apps_alarm_state_and_knows_configured_gauges(sink_of):
    def alarm_state(gauge: str) -> dict | None:
        return {"gauge": gauge, "alarms": [{"level": "high", "state": "normal"}]} if gauge == "a" else None

    _, peer = sink_of(gauges=["a", "b"], alarm_state=alarm_state)
    assert get(peer, f"{PREFIX}/**") == {f"{PREFIX}/a/alarm": alarm_state("a")}


def test_alarm_commands_without_handler_are_refused(sink_of):
    _, peer = sink_of()
    assert get(peer, f"{PREFIX}/a/alarm/ack") == {"error": {"error": "alarm commands are not enabled"}}


def test_a_sink_given_its_gauges_leaves_other_gauges_commands_to_their_daemons(sink_of):
    """Several daemons share a prefix: only the owner may answer, or a refusal could win the get."""
    calls = []
    _, peer = sink_of(gauges=["a"], on_command=lambda g, c, p: calls.append((g, c)) or {"ok": True})
    assert get(peer, f"{PREFIX}/a/alarm/ack") == {f"{PREFIX}/a/alarm/ack": {"ok": True}}
    assert get(peer, f"{PREFIX}/b/alarm/ack") == {}
    peer.put(f"{PREFIX}/b/alarm/shelve", b"{}")
    peer.put(f"{PREFIX}/a/alarm/shelve", b"{}")
    assert wait_for(lambda: len(calls) == 2)
    assert calls == [("a", "ack"), ("a", "shelve")]
