"""JSON schemas of the MCAP channels gauged writes (schema encoding ``jsonschema``, messages ``json``).

Foxglove and Lichtblick read these without a plugin: plot ``/gauged/readings.value`` (one gauge:
``/gauged/readings{gauge=="boiler-pressure"}.value``), list ``/gauged/failures`` and
``/gauged/alarms`` in a Raw Messages or Table panel, and show ``/gauged/<camera>/annotated`` in an
Image panel. ``/<camera>/gauged/annotations`` (``foxglove.ImageAnnotations``, the schema Foxglove
publishes, vendored in ``foxglove_schemas/``) overlays the readings on the camera's own image
topic: open the camera recording with the gauged file and tick the channel in the Image panel.
"""

from __future__ import annotations

import json
from importlib.resources import files
from typing import Any

READINGS_TOPIC = "/gauged/readings"
FAILURES_TOPIC = "/gauged/failures"
ALARMS_TOPIC = "/gauged/alarms"


def annotated_topic(camera: str) -> str:
    return f"/gauged/{camera}/annotated"


def annotations_topic(camera: str) -> str:
    return f"/{camera}/gauged/annotations"  # beside the camera's own topics (issue 37)


_NUMBER_OR_NULL = {"type": ["number", "null"]}
_STRING_OR_NULL = {"type": ["string", "null"]}
_FAILURE = {
    "type": "object",
    "properties": {"stage": {"type": "string"}, "reason": {"type": "string"}, "detail": {"type": "string"}},
}

READING_SCHEMA: dict[str, Any] = {
    "title": "gauged.Reading",
    "description": "One published gauge reading (the <prefix>/<gauge>/reading contract).",
    "type": "object",
    "properties": {
        "gauge": {"type": "string"},
        "camera": {"type": "string"},
        "stamp_ns": {"type": "integer", "description": "Frame time, ns since the Unix epoch."},
        "value": _NUMBER_OR_NULL,
        "raw_value": _NUMBER_OR_NULL,
        "unit": _STRING_OR_NULL,
        "quality": {"type": "string", "enum": ["good", "uncertain", "bad", "stale"]},
        "confidence": {"type": "number"},
        "scale": {
            "type": "object",
            "properties": {"min": _NUMBER_OR_NULL, "max": _NUMBER_OR_NULL, "unit": _STRING_OR_NULL,
                           "locked": {"type": "boolean"}},
        },
        "failure": {"oneOf": [{"type": "null"}, _FAILURE]},
    },
}

FAILURE_SCHEMA: dict[str, Any] = {
    "title": "gauged.StageFailure",
    "description": "A reader stage that refused a frame of a gauge, with its machine-readable reason.",
    "type": "object",
    "properties": {
        "gauge": {"type": "string"},
        "camera": {"type": "string"},
        "stamp_ns": {"type": "integer"},
        **_FAILURE["properties"],
    },
}

ALARM_SCHEMA: dict[str, Any] = {
    "title": "gauged.AlarmEvent",
    "description": "An alarm state change (the <prefix>/<gauge>/alarm contract).",
    "type": "object",
    "properties": {
        "gauge": {"type": "string"},
        "stamp_ns": {"type": "integer"},
        "level": {"type": "string"},
        "state": {"type": "string"},
        "value": _NUMBER_OR_NULL,
        "limit": _NUMBER_OR_NULL,
        "message": {"type": "string"},
    },
}

_TIME = {"type": "object", "properties": {"sec": {"type": "integer", "minimum": 0},
                                          "nsec": {"type": "integer", "minimum": 0, "maximum": 999999999}}}

COMPRESSED_IMAGE_SCHEMA: dict[str, Any] = {
    "title": "foxglove.CompressedImage",
    "description": "A compressed image",
    "type": "object",
    "properties": {
        "timestamp": _TIME,
        "frame_id": {"type": "string"},
        "data": {"type": "string", "contentEncoding": "base64"},
        "format": {"type": "string"},
    },
}

IMAGE_ANNOTATIONS_SCHEMA: dict[str, Any] = json.loads(
    files("gauged.sinks").joinpath("foxglove_schemas/ImageAnnotations.json").read_text(encoding="utf-8"))
