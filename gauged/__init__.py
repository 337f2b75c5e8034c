"""gauged: reads analog gauges from camera frames and publishes readings, alarms and metrics."""

from importlib import metadata as _metadata

try:
    __version__ = _metadata.version("gauged")
except _metadata.PackageNotFoundError:  # running from a source tree that was never installed
    __version__ = "0.0.0+unknown"

__all__ = ["__version__"]
