from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from gauged.alarms.config import AlarmsConfig
from gauged.alarms.lifecycle import AlarmState
from gauged.tracking.config import SmoothingConfig
from gauged.tracking.state_file import read_json, restore_tracker, save_tracker, state_path, write_json_atomic
from gauged.tracking.tracker import GaugeTracker
from gauged.types import RawReading, ScaleInfo

NS = 1_000_000_000


def tracker() -> GaugeTracker:
    return GaugeTracker("boiler", "cam1", SmoothingConfig(), AlarmsConfig(high=8.0), ScaleInfo(0.0, 10.0, "bar"))


def active_tracker() -> GaugeTracker:
    t = tracker()
    for i in range(10):
        t.update(RawReading("boiler", "cam1", i * NS // 10, 8.5, "bar", 1.0))
    return t


def test_save_tracker_writes_the_documented_format(tmp_path: Path) -> None:
    path = save_tracker(active_tracker(), tmp_path / "state", 5 * NS)
    assert path == state_path(tmp_path / "state", "boiler") == tmp_path / "state" / "boiler.json"
    data = json.loads(path.read_text())
    assert {k: data[k] for k in ("format", "version", "gauge", "saved_ns")} == {
        "format": "gauged-tracker-state", "version": 1, "gauge": "boiler", "saved_ns": 5 * NS}
    assert data["last_good"] == {"value": pytest.approx(8.5), "stamp_ns": 9 * NS // 10, "unit": "bar"}
    assert data["alarms"]["high"]["state"] == "active_unacknowledged" and data["alarms"]["high"]["active"] is True
    assert sorted(p.name for p in path.parent.iterdir()) == ["boiler.json"]  # no temporary file left


def test_restore_tracker_round_trips_states_and_last_good(tmp_path: Path) -> None:
    before = active_tracker()
    before.command("shelve", {"level": "high", "who": "bob", "why": "swap", "duration_s": 600}, 1 * NS)
    save_tracker(before, tmp_path, 2 * NS)
    after = tracker()
    assert restore_tracker(after, tmp_path, 3 * NS, 60.0)
    assert after.alarm_status() == before.alarm_status()
    assert after.smoother.last_good == before.smoother.last_good


def test_restore_tracker_expired_shelve_ends_on_the_first_tick(tmp_path: Path) -> None:
    before = active_tracker()
    before.command("shelve", {"level": "high", "who": "bob", "why": "swap", "duration_s": 60}, 1 * NS)
    save_tracker(before, tmp_path, 2 * NS)
    after = tracker()
    restore_tracker(after, tmp_path, 100 * NS, 3600.0)
    _, events = after.tick(100 * NS)
    assert [(e.transition.value, e.state) for e in events] == [("shelve_expired", AlarmState.ACTIVE_UNACKNOWLEDGED)]


@pytest.mark.parametrize(
    ("content", "warning"),
    [
        (b"", "not valid JSON"),
        (b'{"format": "gauged-tracker-state", "vers', "not valid JSON"),
        (b"\x00\xff\xfe garbage", "cannot read"),
        (b"[1, 2, 3]", "expected a JSON object"),
        (b'{"format": "something-else"}', "not a gauged tracker state"),
        (b'{"format": "gauged-tracker-state", "version": 99}', "unsupported version 99"),
        (b'{"format": "gauged-tracker-state", "version": 1, "gauge": "tank", "saved_ns": 0}', "belongs to gauge 'tank'"),
        (b'{"format": "gauged-tracker-state", "version": 1, "gauge": "boiler", "saved_ns": "soon"}', "saved_ns"),
        (b'{"format": "gauged-tracker-state", "version": 1, "gauge": "boiler", "saved_ns": 0, '
         b'"last_good": {"value": NaN, "stamp_ns": 0}}', "holds NaN"),
    ],
)
def test_restore_tracker_corrupt_file_warns_and_starts_fresh(tmp_path: Path, content: bytes, warning: str) -> None:
    (tmp_path / "boiler.json").write_bytes(content)
    t = tracker()
    result = restore_tracker(t, tmp_path, 0, 3600.0)
    assert not result and any(warning in w for w in result.warnings), result
    assert all(status.state is AlarmState.NORMAL for status in t.alarm_status())


def test_restore_tracker_unreadable_path_warns(tmp_path: Path) -> None:
    (tmp_path / "boiler.json").mkdir()
    result = restore_tracker(tracker(), tmp_path, 0, 3600.0)
    assert not result and "cannot read" in result.warnings[0]


def test_restore_tracker_without_a_file_is_a_quiet_fresh_start(tmp_path: Path) -> None:
    result = restore_tracker(tracker(), tmp_path / "missing", 0, 3600.0)
    assert not result and result.warnings == () and "no saved state" in result.message


@pytest.mark.parametrize(("now_s", "word"), [(4000.0, "old"), (-4000.0, "in the future")])
def test_restore_tracker_ignores_state_outside_max_age(tmp_path: Path, now_s: float, word: str) -> None:
    save_tracker(active_tracker(), tmp_path, 0)
    t = tracker()
    result = restore_tracker(t, tmp_path, round(now_s * NS), 3600.0)
    assert not result and word in result.message and result.warnings == ()
    assert t.alarms.alarms["high"].state is AlarmState.NORMAL


def test_restore_tracker_keeps_good_parts_of_a_damaged_state(tmp_path: Path) -> None:
    data = active_tracker().snapshot(0)
    data["alarms"]["high"]["state"] = "flashing"
    data["alarms"]["low"] = {"state": "normal", "active": False}
    data["last_good"] = {"value": "high"}
    write_json_atomic(tmp_path / "boiler.json", data)
    t = tracker()
    result = restore_tracker(t, tmp_path, 0, 3600.0)
    assert result
    assert any("flashing" in w for w in result.warnings)
    assert any("'low' is no longer configured" in w for w in result.warnings)
    assert any("last_good" in w for w in result.warnings)
    assert t.alarms.alarms["high"].state is AlarmState.NORMAL


def test_write_json_atomic_leaves_the_old_file_when_writing_fails(tmp_path: Path) -> None:
    path = tmp_path / "boiler.json"
    write_json_atomic(path, {"a": 1})
    with pytest.raises(ValueError):
        write_json_atomic(path, {"a": math.nan})
    assert read_json(path) == ({"a": 1}, "")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["boiler.json"]


json_values = st.recursive(
    st.none() | st.booleans() | st.integers() | st.floats(allow_nan=False, allow_infinity=False) | st.text(max_size=10),
    lambda inner: st.lists(inner, max_size=4) | st.dictionaries(st.text(max_size=10), inner, max_size=4),
    max_leaves=20)
headers = st.fixed_dictionaries({"format": st.just("gauged-tracker-state"), "version": st.just(1),
                                 "gauge": st.just("boiler"), "saved_ns": st.just(0)})


@settings(suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(st.one_of(json_values, headers.flatmap(
    lambda h: st.dictionaries(st.sampled_from(["last_good", "alarms"]), json_values).map(lambda d: {**h, **d}))))
def test_restore_tracker_never_raises_on_any_json(tmp_path: Path, data: Any) -> None:
    write_json_atomic(tmp_path / "boiler.json", {"x": data} if not isinstance(data, dict) else data)
    result = restore_tracker(tracker(), tmp_path, 0, 3600.0)
    assert isinstance(result.message, str)
