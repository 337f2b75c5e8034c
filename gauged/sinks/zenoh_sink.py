"""Readings and alarms on Zenoh, a queryable with the latest state, and a liveliness token.

Keys (``<prefix>`` from ``outputs.zenoh.prefix``; payloads JSON, encoding ``application/json``):

- put ``<prefix>/<gauge>/reading``: the reading contract (:meth:`gauged.types.Reading.to_dict`);
- put ``<prefix>/<gauge>/alarm``: each alarm state change, as the app's event dict;
- put ``<prefix>/<gauge>/annotations`` (with ``annotations``, the default): the gauge's overlay on
  each frame of its camera, a ``foxglove.ImageAnnotations`` message stamped with the image's time
  (:mod:`gauged.sinks.annotations`; encoding ``application/json;foxglove.ImageAnnotations``). Per
  gauge, not per camera, because gauge ids are what is unique among the daemons sharing a prefix;
  a viewer ticks the overlays of the gauges it shows. The queryable does not answer them;
- queryable ``<prefix>/**``: answers a ``get`` with one reply per matching key: the latest reading
  on ``<prefix>/<gauge>/reading`` and the alarm state on ``<prefix>/<gauge>/alarm`` (one document
  per key, because a get's default consolidation keeps one reply per key). The alarm state is what
  the app's ``alarm_state(gauge)`` returns when it gives one (e.g. built from
  ``GaugeAlarms.status()``), else the sink's own summary of the events it published:
  ``{gauge, stamp_ns, active: [annunciated levels], levels: {level: last event of that level}}``;
- liveliness token ``<prefix>/@alive/<node>`` while the sink is open;
- commands: a ``get`` or a ``put`` on ``<prefix>/<gauge>/alarm/<kind>`` (``ack``, ``shelve``,
  ``unshelve``: :data:`gauged.alarms.commands.COMMAND_KINDS`) calls the app's
  ``on_command(gauge, kind, payload_bytes) -> reply dict``, for its own ``gauges`` only when it was
  given them (the other daemons of the site answer for theirs); a get receives that dict as
  its reply (or a reply error), a put's result is logged. Only exact keys are commands: a wildcard
  get such as ``<prefix>/**`` never acknowledges anything. ``on_command`` runs on a Zenoh thread, so
  it must be quick and thread-safe.
"""

from __future__ import annotations

import logging
import threading
from collections.abc import Callable, Iterable, Mapping
from typing import Any

import zenoh

from gauged.alarms.commands import COMMAND_KINDS
from gauged.sinks.base import AlarmEvent, Overlays, SinkBase, alarm_is_active, to_json
from gauged.types import Reading

log = logging.getLogger(__name__)

CommandHandler = Callable[[str, str, bytes], Mapping[str, Any]]
AlarmStateProvider = Callable[[str], Mapping[str, Any] | None]
JSON = zenoh.Encoding.APPLICATION_JSON
ANNOTATIONS_JSON = JSON.with_schema("foxglove.ImageAnnotations")


class ZenohSink(SinkBase):
    """Publishes on the daemon's Zenoh session (which the app owns and closes)."""

    name = "zenoh"

    def __init__(self, session: zenoh.Session, prefix: str, node: str, *, gauges: Iterable[str] = (),
                 on_command: CommandHandler | None = None, alarm_state: AlarmStateProvider | None = None,
                 annotations: bool = True) -> None:
        self.prefix = prefix
        self.annotations = annotations
        self._session = session
        self._on_command = on_command
        self._alarm_state = alarm_state
        self._lock = threading.Lock()
        self._gauges = set(gauges)  # answered by the queryable even before their first reading
        self._readings: dict[str, bytes] = {}
        self._alarms: dict[str, dict[str, dict[str, Any]]] = {}
        self._publishers: dict[str, Any] = {}
        self._token = session.liveliness().declare_token(f"{prefix}/@alive/{node}")
        self._queryable = session.declare_queryable(f"{prefix}/**", self._on_query)
        self._subscribers = [session.declare_subscriber(f"{prefix}/*/alarm/{command}", self._on_command_put)
                             for command in COMMAND_KINDS] if on_command is not None else []

    def publish_reading(self, reading: Reading) -> None:
        payload = to_json(reading.to_dict())
        with self._lock:
            self._readings[reading.gauge] = payload
        self._publisher(f"{self.prefix}/{reading.gauge}/reading").put(payload)

    def publish_alarm(self, event: AlarmEvent) -> None:
        gauge = str(event["gauge"])
        with self._lock:
            self._alarms.setdefault(gauge, {})[str(event.get("level", ""))] = dict(event)
        self._publisher(f"{self.prefix}/{gauge}/alarm").put(to_json(event))

    def publish_annotations(self, camera: str, stamp_ns: int, overlays: Overlays) -> None:
        if self.annotations:
            for gauge, message in overlays.items():
                self._publisher(f"{self.prefix}/{gauge}/annotations", ANNOTATIONS_JSON).put(to_json(message))

    def _publisher(self, key: str, encoding: zenoh.Encoding = JSON) -> Any:
        publisher = self._publishers.get(key)
        if publisher is None:
            publisher = self._publishers[key] = self._session.declare_publisher(key, encoding=encoding)
        return publisher

    def alarm_state(self, gauge: str) -> Mapping[str, Any] | None:
        """The alarm state document of one gauge (what a get on ``<prefix>/<gauge>/alarm`` returns)."""
        if self._alarm_state is not None:
            return self._alarm_state(gauge)
        with self._lock:
            levels = {level: dict(event) for level, event in self._alarms.get(gauge, {}).items()}
        return {"gauge": gauge,
                "stamp_ns": max((int(e.get("stamp_ns", 0)) for e in levels.values()), default=None),
                "active": sorted(level for level, event in levels.items() if alarm_is_active(event)),
                "levels": levels}

    # -- Zenoh threads --------------------------------------------------------------------------------
    def _command_of(self, key: str) -> tuple[str, str] | None:
        """(gauge, command) when ``key`` is exactly ``<prefix>/<gauge>/alarm/<command>``."""
        rest = key[len(self.prefix) + 1:].split("/") if key.startswith(self.prefix + "/") else []
        if len(rest) == 3 and rest[1] == "alarm" and rest[2] in COMMAND_KINDS and "*" not in rest[0] \
                and not rest[0].startswith("$"):
            return rest[0], rest[2]
        return None

    def _on_query(self, query: zenoh.Query) -> None:
        # ``with query`` finalizes the query on return, even if something (a log record holding an
        # exception and its frames) still references it; otherwise the getter waits for its timeout.
        with query:
            self._answer(query)

    def _answer(self, query: zenoh.Query) -> None:
        key = str(query.key_expr)
        command = self._command_of(key)
        try:
            if command is not None:
                if self._owns(command[0]):
                    self._answer_command(query, key, *command)
                return
            with self._lock:
                readings = dict(self._readings)
                gauges = sorted(self._gauges | set(readings) | set(self._alarms))
            for gauge in gauges:
                reading_key = f"{self.prefix}/{gauge}/reading"
                if gauge in readings and query.key_expr.intersects(reading_key):
                    query.reply(reading_key, readings[gauge], encoding=JSON)
                alarm_key = f"{self.prefix}/{gauge}/alarm"
                if query.key_expr.intersects(alarm_key) and (state := self.alarm_state(gauge)) is not None:
                    query.reply(alarm_key, to_json(state), encoding=JSON)
        except Exception:  # noqa: BLE001 - never raise into Zenoh's thread
            log.exception("zenoh sink: answering query %s failed", key)

    def _owns(self, gauge: str) -> bool:
        """A sink told its gauges leaves the others' commands to the daemons that own them (several
        daemons share one prefix, and a get's consolidation keeps one reply per key)."""
        return not self._gauges or gauge in self._gauges

    def _answer_command(self, query: zenoh.Query, key: str, gauge: str, command: str) -> None:
        if self._on_command is None:
            query.reply_err(to_json({"error": "alarm commands are not enabled"}), encoding=JSON)
            return
        payload = query.payload.to_bytes() if query.payload is not None else b""
        try:
            reply = self._on_command(gauge, command, payload)
        except Exception as err:  # noqa: BLE001 - the caller gets the error, the daemon goes on
            error = f"{type(err).__name__}: {err}"
            log.warning("zenoh sink: %s of %s failed: %s", command, gauge, error)
            query.reply_err(to_json({"error": error}), encoding=JSON)
            return
        query.reply(key, to_json(reply), encoding=JSON)

    def _on_command_put(self, sample: zenoh.Sample) -> None:
        command = self._command_of(str(sample.key_expr))
        if command is None or self._on_command is None or sample.kind != zenoh.SampleKind.PUT \
                or not self._owns(command[0]):
            return
        try:
            reply = self._on_command(command[0], command[1], sample.payload.to_bytes())
            log.info("zenoh sink: %s of %s by put: %s", command[1], command[0], dict(reply))
        except Exception as err:  # noqa: BLE001
            log.warning("zenoh sink: %s of %s by put failed: %s: %s", command[1], command[0], type(err).__name__, err)

    def close(self) -> None:
        """Undeclare everything (the liveliness token last, so watchers see the daemon go)."""
        for entity in [*self._subscribers, self._queryable, *self._publishers.values(), self._token]:
            try:
                entity.undeclare()
            except Exception as err:  # noqa: BLE001 - a closed session already dropped it
                log.debug("zenoh sink: undeclare failed: %s", err)
        self._subscribers, self._publishers = [], {}
