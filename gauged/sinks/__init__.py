"""Outputs of gauged: Zenoh, MCAP and Prometheus, one small plugin module each.

Every plugin subclasses :class:`~gauged.sinks.base.SinkBase` and is wrapped in a
:class:`~gauged.sinks.buffered.BufferedSink`, which owns buffering, errors and self-metrics.
:func:`open_sinks` builds the enabled outputs of a configuration, wrapped and ready.
"""

from __future__ import annotations

import logging
from collections.abc import Iterable
from typing import TYPE_CHECKING

from gauged.sinks.base import AlarmEvent, Sink, SinkBase
from gauged.sinks.buffered import BufferedSink

if TYPE_CHECKING:
    import zenoh

    from gauged.metrics import Metrics
    from gauged.sinks.config import OutputsConfig
    from gauged.sinks.zenoh_sink import AlarmStateProvider, CommandHandler

__all__ = ["AlarmEvent", "BufferedSink", "Sink", "SinkBase", "open_sinks"]

log = logging.getLogger(__name__)


def open_sinks(outputs: OutputsConfig, *, metrics: Metrics, session: zenoh.Session | None, node: str,
               gauges: Iterable[str] = (), failure_pairs: Iterable[tuple[str, str]] = (),
               on_command: CommandHandler | None = None, alarm_state: AlarmStateProvider | None = None,
               name_prefix: str = "gauged") -> list[BufferedSink]:
    """The enabled outputs, each wrapped; on an error the ones already open are closed and it re-raises.

    ``gauges`` and ``failure_pairs`` pre-create the failure counters (and ``gauges`` are answered by
    the queryable from the start); ``on_command`` receives alarm ack/shelve/unshelve commands from
    Zenoh and ``alarm_state`` answers alarm-state queries (see :mod:`gauged.sinks.zenoh_sink`);
    ``name_prefix`` starts the MCAP file names (e.g. the site).
    """
    gauges = list(gauges)
    opened: list[BufferedSink] = []
    try:
        if outputs.prometheus.enabled:
            from gauged.sinks.prometheus_sink import PrometheusSink

            prometheus = PrometheusSink.from_config(outputs.prometheus, metrics, gauges=gauges,
                                                    failure_pairs=failure_pairs)
            opened.append(BufferedSink(prometheus, metrics))
        if outputs.mcap.enabled:
            from gauged.sinks.mcap_sink import McapSink

            opened.append(BufferedSink(McapSink.from_config(outputs.mcap, name_prefix), metrics))
        if outputs.zenoh.enabled:
            if session is None:
                raise ValueError("outputs.zenoh is enabled but no zenoh session is open")
            from gauged.sinks.zenoh_sink import ZenohSink

            zenoh_sink = ZenohSink(session, outputs.zenoh.prefix, node, gauges=gauges, on_command=on_command,
                                   alarm_state=alarm_state, annotations=outputs.zenoh.annotations)
            opened.append(BufferedSink(zenoh_sink, metrics))
    except Exception:
        for sink in reversed(opened):
            sink.close()
        raise
    return opened
