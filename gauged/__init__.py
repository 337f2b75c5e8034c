"""gauged: reads analog gauges from camera frames and publishes readings, alarms and metrics."""

import os as _os
from importlib import metadata as _metadata

# onnxruntime uploads usage telemetry unless told not to; a plant daemon must not phone home.
_os.environ.setdefault("ORT_DISABLE_TELEMETRY", "1")

try:
    __version__ = _metadata.version("gauged")
except _metadata.PackageNotFoundError:  # running from a source tree that was never installed
    __version__ = "0.0.0+unknown"

__all__ = ["__version__"]
