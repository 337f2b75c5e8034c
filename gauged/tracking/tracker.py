"""One object per gauge for the daemon: smoothing, quality and alarms, and their saved state.

>>> from gauged.alarms.config import AlarmsConfig
>>> from gauged.tracking.config import SmoothingConfig
>>> from gauged.types import RawReading
>>> tracker = GaugeTracker("boiler", "cam1", SmoothingConfig(), AlarmsConfig(high=8.0))
>>> reading, events = tracker.update(RawReading("boiler", "cam1", 0, 5.0, "bar", 0.9))
>>> reading.quality.value, events
('uncertain', [])
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from gauged.alarms.commands import CommandResult, handle_alarm_command
from gauged.alarms.config import AlarmsConfig
from gauged.alarms.gauge_alarms import GaugeAlarms
from gauged.alarms.lifecycle import AlarmEvent, AlarmStatus
from gauged.tracking.config import SmoothingConfig
from gauged.tracking.gauge_smoother import NS_PER_S, GaugeSmoother
from gauged.types import FrameOutcome, RawReading, Reading, ScaleInfo

if TYPE_CHECKING:  # the config tree imports this package's config; a runtime import would loop
    from gauged.config.model import GaugeConfig

STATE_FORMAT = "gauged-tracker-state"
STATE_VERSION = 1


@dataclass(frozen=True, slots=True)
class RestoreResult:
    """What :meth:`GaugeTracker.restore` did: falsy when nothing was restored.

    ``message`` is for an info log line; ``warnings`` (corrupt parts, dropped levels) for warnings.
    """

    restored: bool
    message: str
    warnings: tuple[str, ...] = ()

    def __bool__(self) -> bool:
        return self.restored


class GaugeTracker:
    """Smoother plus alarms of one gauge. Feed it every raw reading and a periodic :meth:`tick`."""

    def __init__(self, gauge: str, camera: str, smoothing: SmoothingConfig, alarms: AlarmsConfig,
                 scale: ScaleInfo | None = None) -> None:
        self.gauge = gauge
        self.camera = camera
        self.smoother = GaugeSmoother(gauge, camera, smoothing, alarms.stale_after_s, scale)
        self.alarms = GaugeAlarms(gauge, alarms)
        self.last_reading: Reading | None = None

    @classmethod
    def from_config(cls, config: GaugeConfig) -> GaugeTracker:
        """Build from a gauge's config entry (its scale, if given, is the prior for noise levels)."""
        scale = None if config.scale is None else ScaleInfo(config.scale.min, config.scale.max, config.scale.unit)
        return cls(config.id, config.camera, config.smoothing, config.alarms, scale)

    def update(self, raw: RawReading, *, scale_locked: bool = False) -> tuple[Reading, list[AlarmEvent]]:
        """One raw reading of this gauge in: the reading to publish and the alarm state changes."""
        if raw.gauge != self.gauge:
            raise ValueError(f"reading of gauge {raw.gauge!r} given to the tracker of {self.gauge!r}")
        last = self.smoother.last_frame_ns
        if last is not None and raw.stamp_ns < last:
            # A looped recording or a camera clock reset: start a new track rather than compute
            # negative time steps; alarm states stay, their delays restart.
            self.smoother.reset(raw.stamp_ns)
            self.alarms.rebase()
        smoothed = self.smoother.update(raw, scale_locked)
        self.last_reading = smoothed.reading
        return smoothed.reading, self.alarms.update(smoothed.reading, smoothed.outcome)

    def tick(self, now_ns: int) -> tuple[Reading | None, list[AlarmEvent]]:
        """Let time pass without a frame: a ``stale`` reading when staleness begins, and alarm changes
        (stale alarm, expired shelves). ``now_ns`` must be in the frame time base."""
        reading = self.smoother.tick(now_ns)
        if reading is None:
            return None, self.alarms.tick(now_ns)
        self.last_reading = reading
        return reading, self.alarms.update(reading, FrameOutcome.NO_FRAME)

    def command(self, kind: str, payload: bytes | str | Mapping[str, Any], now_ns: int) -> CommandResult:
        """An operator command (``ack``, ``shelve``, ``unshelve``) with its JSON payload."""
        return handle_alarm_command(self.alarms, kind, payload, now_ns)

    def alarm_status(self) -> list[AlarmStatus]:
        return self.alarms.status()

    @property
    def dirty(self) -> bool:
        """An alarm state or shelve changed since the last :meth:`snapshot`: save soon."""
        return self.alarms.dirty

    # --- persistence --------------------------------------------------------------------------

    def snapshot(self, now_ns: int) -> dict[str, Any]:
        """The state to save (JSON-ready); ``now_ns`` is stored as ``saved_ns`` to judge its age later."""
        last_good = self.smoother.last_good
        unit = self.last_reading.unit if self.last_reading is not None else None
        return {
            "format": STATE_FORMAT,
            "version": STATE_VERSION,
            "gauge": self.gauge,
            "saved_ns": int(now_ns),
            "last_good": None if last_good is None else {"value": last_good[0], "stamp_ns": last_good[1], "unit": unit},
            "alarms": self.alarms.snapshot(),
        }

    def restore(self, saved: Mapping[str, Any], now_ns: int, max_age_s: float) -> RestoreResult:
        """Take back a :meth:`snapshot` unless it is malformed, of another gauge, or older than ``max_age_s``.

        Never raises on bad content: a refused state is a falsy result saying why, and the tracker
        starts fresh.
        """
        problem = _check_header(saved, self.gauge)
        if problem:
            return RestoreResult(False, f"saved state of {self.gauge} ignored: {problem}", (problem,))
        age_s = (now_ns - saved["saved_ns"]) / NS_PER_S
        if abs(age_s) > max_age_s:
            when = "old" if age_s > 0 else "in the future"
            return RestoreResult(False, f"saved state of {self.gauge} is {abs(age_s):.0f} s {when} "
                                        f"(state.max_age_s {max_age_s:g}); starting fresh")
        warnings: list[str] = []
        last_good = saved.get("last_good")
        if last_good is not None:
            value, stamp = (last_good.get("value"), last_good.get("stamp_ns")) if isinstance(last_good, Mapping) else (None, None)
            if (isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)
                    and isinstance(stamp, int) and not isinstance(stamp, bool)):
                self.smoother.restore_last_good(float(value), stamp)
            else:
                warnings.append(f"last_good of {self.gauge} is malformed ({last_good!r}); not restored")
        warnings.extend(self.alarms.restore(saved.get("alarms", {})))
        return RestoreResult(True, f"restored state of {self.gauge} saved {age_s:.0f} s ago", tuple(warnings))


def _check_header(saved: Any, gauge: str) -> str:
    """Why a saved state cannot be used at all, or ``""``."""
    if not isinstance(saved, Mapping):
        return f"expected a JSON object, got {type(saved).__name__}"
    if saved.get("format") != STATE_FORMAT:
        return f"not a gauged tracker state (format {saved.get('format')!r})"
    if saved.get("version") != STATE_VERSION:
        return f"unsupported version {saved.get('version')!r} (this build reads {STATE_VERSION})"
    if saved.get("gauge") != gauge:
        return f"it belongs to gauge {saved.get('gauge')!r}"
    if not isinstance(saved.get("saved_ns"), int) or isinstance(saved.get("saved_ns"), bool):
        return "saved_ns is missing or not an integer"
    return ""
