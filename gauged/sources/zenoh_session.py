"""Open the daemon's one Zenoh session from its configuration (shared by Zenoh sources and the sink)."""

from __future__ import annotations

import json
import logging

import zenoh

from gauged.config.model import ZenohConfig

log = logging.getLogger(__name__)


def zenoh_config(config: ZenohConfig) -> zenoh.Config:
    """The ``zenoh.Config`` of a :class:`~gauged.config.model.ZenohConfig` (mode, endpoints, scouting)."""
    conf = zenoh.Config()
    conf.insert_json5("mode", json.dumps(config.mode))
    conf.insert_json5("connect/endpoints", json.dumps(config.connect))
    conf.insert_json5("listen/endpoints", json.dumps(config.listen))
    conf.insert_json5("scouting/multicast/enabled", json.dumps(config.multicast_scouting))
    return conf


def open_session(config: ZenohConfig) -> zenoh.Session:
    """Open a session; raises ``zenoh.ZError`` when an endpoint cannot be used."""
    session = zenoh.open(zenoh_config(config))
    log.info("zenoh session %s open (mode %s, connect %s, listen %s)", session.zid(), config.mode,
             config.connect or "-", config.listen or "-")
    return session
