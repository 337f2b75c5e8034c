"""Frame sources: where camera frames come from, one small module per transport.

Every source serves one camera through the pull-style :class:`FrameSource` protocol. The producer
side (a Zenoh callback, an MCAP reader thread) hands frames to a one-slot, newest-wins mailbox and
never blocks; the camera's worker thread calls ``next_frame(timeout)``, which decodes the newest
frame in the worker's own thread. Frames replaced before they were taken are counted in
``gauged_frames_dropped_total{camera}``; undecodable ones in ``gauged_frames_invalid_total``.

Typical worker loop (the app owns it)::

    source = make_source(camera, metrics=metrics, session=session)
    source.start()
    while not stopping.is_set() and not source.finished:
        frame = source.next_frame(timeout=0.5)
        if frame is not None:
            read(frame)
    source.stop()
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Protocol

from gauged.types import Frame

if TYPE_CHECKING:
    import zenoh

    from gauged.config.model import CameraConfig
    from gauged.metrics import Metrics


class FrameSource(Protocol):
    """The frames of one camera."""

    camera: str

    def start(self) -> None:
        """Begin receiving (declare the subscriber, start the reader thread)."""

    def next_frame(self, timeout: float | None = None) -> Frame | None:
        """The newest frame, decoded; None after ``timeout`` seconds without one, or once stopped."""

    @property
    def finished(self) -> bool:
        """True when no frame will ever come again (a replayed recording reached its end)."""

    def stop(self) -> None:
        """Stop receiving and wake a consumer blocked in ``next_frame``. Idempotent."""


def make_source(camera: CameraConfig, *, metrics: Metrics | None = None,
                session: zenoh.Session | None = None) -> FrameSource:
    """The source selected by ``camera.source.type`` (``zenoh`` needs the daemon's session)."""
    from gauged.sources.config import McapSourceConfig, ZenohSourceConfig

    config = camera.source
    if isinstance(config, ZenohSourceConfig):
        if session is None:
            raise ValueError(f"camera {camera.id}: a zenoh source needs a zenoh session")
        from gauged.sources.zenoh_source import ZenohSource

        return ZenohSource.from_config(camera.id, config, session, metrics)
    if isinstance(config, McapSourceConfig):
        from gauged.sources.mcap_source import McapSource

        return McapSource.from_config(camera.id, config, metrics)
    raise TypeError(f"camera {camera.id}: unknown source type {type(config).__name__}")
