"""Operator commands on a gauge's alarms: acknowledge, shelve, unshelve.

The daemon routes a Zenoh put or query on ``<prefix>/<gauge>/alarm/<kind>`` (``kind`` one of
:data:`COMMAND_KINDS`) here with its payload, a JSON object::

    {"level": "high" | "all", "who": "alice", "why": "pump swapped", "duration_s": 600}

``level`` and ``who`` are required; ``why`` is required to shelve (ISA-18.2 asks for a reason) and
optional otherwise; ``duration_s`` only goes with ``shelve`` (default ``alarms.shelve_default_s``, at
most ``alarms.shelve_max_s``). The answer is a :class:`CommandResult`, whose ``to_dict()`` is what
the daemon replies with; a malformed command is a result with ``ok`` false, never an exception.
"""

from __future__ import annotations

import json
import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

from gauged.alarms.gauge_alarms import ALL, GaugeAlarms
from gauged.alarms.lifecycle import AlarmEvent

COMMAND_KINDS = ("ack", "shelve", "unshelve")
MAX_PAYLOAD_BYTES = 4096
MAX_TEXT_CHARS = 200  # who/why end up in logs and MCAP; a name or a sentence, not a document
_KEYS = {"level", "who", "why", "duration_s"}


@dataclass(frozen=True, slots=True)
class AlarmCommand:
    """A parsed, well-formed command (whether the gauge has that level is checked when applied)."""

    kind: str
    level: str
    who: str
    why: str | None = None
    duration_s: float | None = None


@dataclass(frozen=True, slots=True)
class CommandResult:
    """The outcome of a command: falsy when refused, with a message for the person who sent it."""

    ok: bool
    message: str
    events: tuple[AlarmEvent, ...] = ()

    def __bool__(self) -> bool:
        return self.ok

    def to_dict(self) -> dict[str, Any]:
        return {"ok": self.ok, "message": self.message, "events": [event.to_dict() for event in self.events]}


def _refuse(message: str) -> CommandResult:
    return CommandResult(False, message)


def _text(body: Mapping[str, Any], key: str, required: bool) -> str | None | CommandResult:
    value = body.get(key)
    if value is None:
        return _refuse(f"'{key}' is required") if required else None
    if not isinstance(value, str) or not value.strip():
        return _refuse(f"'{key}' must be a non-empty string")
    if len(value) > MAX_TEXT_CHARS:
        return _refuse(f"'{key}' is longer than {MAX_TEXT_CHARS} characters")
    return value.strip()


def parse_alarm_command(kind: str, payload: bytes | str | Mapping[str, Any]) -> AlarmCommand | CommandResult:
    """Parse a command payload; returns the command, or a refusing :class:`CommandResult` saying why."""
    if kind not in COMMAND_KINDS:
        return _refuse(f"unknown command {kind!r} (one of {', '.join(COMMAND_KINDS)})")
    if isinstance(payload, (bytes, bytearray)):
        if len(payload) > MAX_PAYLOAD_BYTES:
            return _refuse(f"payload larger than {MAX_PAYLOAD_BYTES} bytes")
        try:
            payload = bytes(payload).decode("utf-8")
        except UnicodeDecodeError:
            return _refuse("payload is not UTF-8 text")
    if isinstance(payload, str):
        try:
            payload = json.loads(payload)
        except json.JSONDecodeError as exc:
            return _refuse(f"payload is not JSON: {exc.msg} at character {exc.pos}")
    if not isinstance(payload, Mapping):
        return _refuse('payload must be a JSON object like {"level": "high", "who": "...", "why": "..."}')
    unknown = sorted(set(payload) - _KEYS)
    if unknown:
        return _refuse(f"unknown key(s) {', '.join(map(repr, unknown))} (allowed: {', '.join(sorted(_KEYS))})")
    level = _text(payload, "level", required=True)
    who = _text(payload, "who", required=True)
    why = _text(payload, "why", required=kind == "shelve")
    for field in (level, who, why):
        if isinstance(field, CommandResult):
            return field
    duration = payload.get("duration_s")
    if duration is not None:
        if kind != "shelve":
            return _refuse("'duration_s' goes only with shelve")
        if isinstance(duration, bool) or not isinstance(duration, (int, float)) or not math.isfinite(duration) or duration <= 0:
            return _refuse("'duration_s' must be a number of seconds > 0")
        duration = float(duration)
    return AlarmCommand(kind, str(level), str(who), why if isinstance(why, str) else None, duration)


def apply_alarm_command(alarms: GaugeAlarms, command: AlarmCommand, now_ns: int) -> CommandResult:
    """Carry out a parsed command at ``now_ns`` (the daemon's time in the frame time base)."""
    if command.level != ALL and command.level not in alarms.alarms:
        return _refuse(f"gauge {alarms.gauge!r} has no {command.level!r} alarm "
                       f"(alarms: {', '.join(alarms.levels)}, or 'all')")
    if command.kind == "ack":
        events = alarms.acknowledge(command.level, command.who, command.why, now_ns)
        if not events:
            return CommandResult(True, f"nothing awaited acknowledgement ({_states(alarms, command.level)})")
        return CommandResult(True, f"acknowledged {', '.join(e.level for e in events)}", tuple(events))
    if command.kind == "shelve":
        duration = command.duration_s if command.duration_s is not None else alarms.config.shelve_default_s
        if duration > alarms.config.shelve_max_s:
            return _refuse(f"duration_s {duration:g} exceeds alarms.shelve_max_s ({alarms.config.shelve_max_s:g})")
        assert command.why is not None  # required for shelve by the parser
        events = alarms.shelve(command.level, command.who, command.why, now_ns, duration)
        return CommandResult(True, f"shelved {command.level} for {duration:g} s", tuple(events))
    events = alarms.unshelve(command.level, command.who, command.why, now_ns)
    if not events:
        return CommandResult(True, f"nothing was shelved ({_states(alarms, command.level)})")
    return CommandResult(True, f"unshelved {', '.join(e.level for e in events)}", tuple(events))


def _states(alarms: GaugeAlarms, level: str) -> str:
    chosen = alarms.levels if level == ALL else (level,)
    return ", ".join(f"{name}: {alarms.alarms[name].state.value}" for name in chosen)


def handle_alarm_command(alarms: GaugeAlarms, kind: str, payload: bytes | str | Mapping[str, Any],
                         now_ns: int) -> CommandResult:
    """Parse and apply in one call: what the daemon's Zenoh handler calls."""
    command = parse_alarm_command(kind, payload)
    if isinstance(command, CommandResult):
        return command
    return apply_alarm_command(alarms, command, now_ns)
