"""Typed configuration: the model tree, its YAML loader, and errors naming key path and line.

Names are imported lazily: the model tree imports the config models of sources, sinks, tracking
and alarms, which themselves import :mod:`gauged.config.errors`; an eager import here would make
that a cycle for whoever imports one of those modules first.
"""

from __future__ import annotations

import importlib
from typing import Any

_EXPORTS = {
    "ConfigError": "gauged.config.errors",
    "ConfigIssue": "gauged.config.errors",
    "FieldIssues": "gauged.config.errors",
    "CameraConfig": "gauged.config.model",
    "GaugeConfig": "gauged.config.model",
    "GaugedConfig": "gauged.config.model",
    "ScaleConfig": "gauged.config.model",
    "default_config_text": "gauged.config.loader",
    "load_config": "gauged.config.loader",
    "load_default_config": "gauged.config.loader",
    "parse_config": "gauged.config.loader",
}

__all__ = sorted(_EXPORTS)


def __getattr__(name: str) -> Any:
    if name not in _EXPORTS:
        raise AttributeError(f"module 'gauged.config' has no attribute {name!r}")
    return getattr(importlib.import_module(_EXPORTS[name]), name)
