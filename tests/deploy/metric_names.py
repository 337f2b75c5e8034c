"""The metric names gauged exports (from gauged/metrics.py itself) and the names a PromQL
expression uses, for checking that rules and dashboards ask for series that exist."""

from __future__ import annotations

import re

from gauged.metrics import Metrics

# Series every scrape has without gauged declaring them.
PROMETHEUS_SERIES = {"up"}
_SUFFIXES = {"counter": ("_total",), "histogram": ("_bucket", "_count", "_sum"), "gauge": ("",)}
_GAUGED_NAME = re.compile(r"\bgauged_[a-z0-9_]+")
_RECORDED_NAME = re.compile(r"\b[a-z_]+:gauged_[a-z0-9_]+:[a-z0-9_]+")


def exported_metric_names() -> set[str]:
    """Every series name a gauged daemon exposes on /metrics."""
    names = set()
    for family in Metrics().registry.collect():
        names.update(family.name + suffix for suffix in _SUFFIXES[family.type])
    return names


def gauged_names_in(expr: str) -> set[str]:
    """The ``gauged_*`` metric names an expression reads (recorded ``level:gauged_...:op`` aside)."""
    return set(_GAUGED_NAME.findall(_RECORDED_NAME.sub(" ", expr)))


def recorded_names_in(expr: str) -> set[str]:
    """The recording-rule names (``level:metric:operations``) an expression reads."""
    return set(_RECORDED_NAME.findall(expr))
