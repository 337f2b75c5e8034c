"""Saving and loading a gauge tracker's state: the only I/O of tracking and alarms.

One JSON file per gauge, ``<state.dir>/<gauge>.json`` (format in docs/alarms.md). Writes are atomic
(temporary file in the same directory, fsync, ``os.replace``, fsync of the directory), so a power
cut leaves either the old file or the new one, never half of one. Reading never raises on bad
content: a corrupt file means a warning and a fresh start.
"""

from __future__ import annotations

import json
import os
import tempfile
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from gauged.tracking.tracker import GaugeTracker, RestoreResult

MAX_STATE_BYTES = 1 << 20  # a gauge's state is a few hundred bytes; anything this big is not ours


def state_path(state_dir: str | Path, gauge: str) -> Path:
    """Where the state of ``gauge`` lives (gauge ids are ``[A-Za-z0-9_.-]+``, safe as file names)."""
    return Path(state_dir) / f"{gauge}.json"


def write_json_atomic(path: Path, data: Mapping[str, Any]) -> None:
    """Write ``data`` as JSON to ``path`` atomically. Raises ``OSError`` (or ``ValueError`` for NaN)."""
    path.parent.mkdir(parents=True, exist_ok=True)
    text = json.dumps(data, indent=1, sort_keys=True, allow_nan=False) + "\n"
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    try:
        with os.fdopen(fd, "w", encoding="utf-8") as handle:
            handle.write(text)
            handle.flush()
            os.fsync(handle.fileno())
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
    try:  # make the rename itself durable; not every file system lets a directory be fsynced
        dir_fd = os.open(path.parent, os.O_RDONLY)
        try:
            os.fsync(dir_fd)
        finally:
            os.close(dir_fd)
    except OSError:
        pass


def read_json(path: Path) -> tuple[Any, str]:
    """``(data, "")`` for a readable JSON file, ``(None, "")`` when there is none, ``(None, why)`` otherwise."""
    try:
        if path.stat().st_size > MAX_STATE_BYTES:
            return None, f"{path} is larger than {MAX_STATE_BYTES} bytes"
        text = path.read_text(encoding="utf-8")
    except FileNotFoundError:
        return None, ""
    except (OSError, UnicodeDecodeError) as exc:
        return None, f"cannot read {path}: {exc}"
    try:
        return json.loads(text, parse_constant=_refuse_constant), ""
    except json.JSONDecodeError as exc:
        return None, f"{path} is not valid JSON ({exc.msg}, line {exc.lineno})"
    except ValueError as exc:
        return None, f"{path}: {exc}"


def _refuse_constant(name: str) -> Any:
    # Python's json reads NaN and Infinity, which are not JSON and would poison the filter.
    raise ValueError(f"holds {name}, which is not a JSON number")


def save_tracker(tracker: GaugeTracker, state_dir: str | Path, now_ns: int) -> Path:
    """Save ``tracker``'s state atomically; returns the file. Raises ``OSError`` when it cannot be written."""
    path = state_path(state_dir, tracker.gauge)
    write_json_atomic(path, tracker.snapshot(now_ns))
    return path


def restore_tracker(tracker: GaugeTracker, state_dir: str | Path, now_ns: int, max_age_s: float) -> RestoreResult:
    """Restore ``tracker`` from its saved state if there is one, readable and young enough. Never raises."""
    path = state_path(state_dir, tracker.gauge)
    data, problem = read_json(path)
    if problem:
        warning = f"state file unusable, starting fresh: {problem}"
        return RestoreResult(False, warning, (warning,))
    if data is None:
        return RestoreResult(False, f"no saved state for {tracker.gauge} at {path}; starting fresh")
    result = tracker.restore(data, now_ns, max_age_s)
    if not result and result.warnings:
        return RestoreResult(False, f"{path}: {result.message}", tuple(f"{path}: {w}" for w in result.warnings))
    return result
