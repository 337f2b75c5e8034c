"""Readings of a replay against the truth channel of a synthetic recording (``/<camera>/truth``)."""

from __future__ import annotations

import json
from collections import Counter, defaultdict
from pathlib import Path

import numpy as np
from mcap.reader import make_reader


def _messages(path: Path, suffix: str):
    with path.open("rb") as stream:
        for _schema, channel, message in make_reader(stream).iter_messages():
            if channel.topic.endswith(suffix):
                yield json.loads(message.data)


def compare(recording: Path, readings: Path) -> dict[str, dict]:
    """Per gauge: frames, failures by reason, and raw/smoothed relative error (|v - true| / span)."""
    truth: dict[tuple[str, int], tuple[float, float]] = {}
    for frame in _messages(recording, "/truth"):
        for gauge in frame["gauges"]:
            truth[(gauge["gauge"], frame["stamp_ns"])] = (gauge["value"], gauge["max"] - gauge["min"])
    raw: dict[str, list[float]] = defaultdict(list)
    smooth: dict[str, list[float]] = defaultdict(list)
    failures: dict[str, Counter] = defaultdict(Counter)
    frames: Counter = Counter()
    for reading in _messages(readings, "/gauged/readings"):
        key = (reading["gauge"], reading["stamp_ns"])
        if key not in truth:
            continue
        value, span = truth[key]
        frames[reading["gauge"]] += 1
        if reading["raw_value"] is None:
            failure = reading.get("failure") or {}
            failures[reading["gauge"]][f"{failure.get('stage')}/{failure.get('reason')}"] += 1
        else:
            raw[reading["gauge"]].append(abs(reading["raw_value"] - value) / span)
        if reading["value"] is not None:
            smooth[reading["gauge"]].append(abs(reading["value"] - value) / span)
    result = {}
    for gauge in sorted(frames):
        r, s = np.asarray(raw[gauge]), np.asarray(smooth[gauge])
        result[gauge] = {
            "frames": frames[gauge], "failures": sum(failures[gauge].values()), "by_reason": dict(failures[gauge]),
            "raw_median": float(np.median(r)) if len(r) else None, "raw_mean": float(r.mean()) if len(r) else None,
            "raw_max": float(r.max()) if len(r) else None,
            "value_median": float(np.median(s)) if len(s) else None, "value_max": float(s.max()) if len(s) else None,
        }
    return result


def format_comparison(result: dict[str, dict]) -> str:
    lines = [f"{'gauge':<18} {'frames':>6} {'failed':>6} {'raw med':>8} {'raw mean':>8} {'raw max':>8} {'value med':>9}"]
    pct = lambda v: "-" if v is None else f"{100 * v:.2f}%"  # noqa: E731
    for gauge, r in result.items():
        lines.append(f"{gauge:<18} {r['frames']:>6} {r['failures']:>6} {pct(r['raw_median']):>8} {pct(r['raw_mean']):>8} "
                     f"{pct(r['raw_max']):>8} {pct(r['value_median']):>9}  {r['by_reason'] or ''}")
    return "\n".join(lines)
