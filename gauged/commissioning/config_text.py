"""The config YAML a commissioning writes: the schema of :mod:`gauged.config.model`, with comments.

Written as text rather than dumped, so each gauge says what was read and how sure it is, suggested
alarm limits stay commented out (the process decides them, not the dial), and a gauge that could not be
read carries ``# TODO: <reason>`` with its ROI and the scale left for the operator.
"""

from __future__ import annotations

import json
import math
import re
from typing import Any

import yaml

from gauged.commissioning.frames import CameraFrames
from gauged.commissioning.survey import GaugeFinding, ScaleRead

ALARM_LOW, ALARM_HIGH, DEADBAND = 0.1, 0.9, 0.01  # suggested limits, as shares of the span


def _scalar(value: Any) -> str:
    """``value`` as a YAML flow scalar: plain when YAML reads it back as the same string, else quoted
    (a unit ``"%"``, a camera id ``"null"`` or ``"1e3"`` must stay strings)."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, float | int):
        return f"{value:g}"
    text = str(value)
    try:
        plain = bool(text) and re.fullmatch(r"[A-Za-z0-9_./-]+", text) is not None and yaml.safe_load(text) == text
    except yaml.YAMLError:
        plain = False
    return text if plain else json.dumps(text)


def _flow(mapping: dict[str, Any]) -> str:
    return "{" + ", ".join(f"{k}: {_scalar(v)}" for k, v in mapping.items() if v is not None) + "}"


def _comment(text: str) -> str:
    return " ".join(text.split())


def _nice(value: float, span: float) -> float:
    """``value`` rounded to a step of about a hundredth of ``span`` (a power of ten)."""
    step = 10.0 ** math.floor(math.log10(abs(span) / 100.0)) if span else 1.0
    return float(f"{round(value / step) * step:.6g}")


def suggested_alarms(scale: ScaleRead) -> dict[str, float]:
    """Limits at :data:`ALARM_LOW` / :data:`ALARM_HIGH` of the span and a deadband of :data:`DEADBAND` of it."""
    span = scale.span
    return {"low": _nice(scale.min + ALARM_LOW * span, span), "high": _nice(scale.min + ALARM_HIGH * span, span),
            "deadband": _nice(DEADBAND * span, span) or _nice(DEADBAND * span, span / 10)}


def _scale_block(gauge: GaugeFinding) -> list[str]:
    scale = gauge.scale
    votes = f"read on {gauge.votes[scale.key]} of {gauge.frames} frame(s)"
    checked = f"the daemon's read of this roi and scale: {gauge.checked} of {gauge.frames}"
    lines: list[str] = []
    fields = {'min': scale.min, 'max': scale.max, 'unit': scale.unit}
    if scale.direction < 0:
        fields["direction"] = "ccw"
    way = "clockwise" if scale.direction > 0 else "counter-clockwise"
    lines.append(f"    scale: {_flow(fields)}   # {way}; {votes}; {checked}")
    if scale.unit is None:
        lines.append("    # TODO: no unit read on the dial: add unit: to the scale")
    if gauge.other_scale is not None:
        other = gauge.other_scale
        if scale.unit and other.unit and other.unit != scale.unit:
            lines.append(f"    primary_unit: {_scalar(scale.unit)}   # the dial also has a {other.min:g}..{other.max:g} "
                         f"{other.unit} scale")
        else:
            lines.append(f"    # the dial also has a {other.min:g}..{other.max:g} {other.unit or ''} scale")
    alarms = suggested_alarms(scale)
    lines.append(f"    # alarms: {_flow(alarms)}   # suggested ({ALARM_LOW:.0%} / {ALARM_HIGH:.0%} of the scale): "
                 "set your process limits")
    return lines


def gauge_block(gauge: GaugeFinding) -> list[str]:
    """The YAML lines of one gauge (list item under ``gauges:``)."""
    lines = [f"  - id: {gauge.id}", f"    camera: {gauge.camera}", f"    roi: [{', '.join(str(v) for v in gauge.roi)}]"]
    if gauge.todo is not None:
        lines.append(f"    # TODO: {_comment(gauge.todo)}")
    if gauge.scale is None:
        lines.append("    # scale: {min: ?, max: ?, unit: ?}   # read the dial; without a scale the daemon "
                     "reads it by OCR and locks it")
    else:
        lines.extend(_scale_block(gauge))
    if gauge.value is not None and gauge.scale is not None:
        unit = gauge.scale.unit if gauge.scale is not None and gauge.scale.unit else ""
        lines.append(f"    # value when commissioned: {gauge.value:.4g} {unit}".rstrip())
    return lines


def config_text(site: str, cameras: list[CameraFrames], gauges: dict[str, list[GaugeFinding]],
                dropped: dict[str, list[GaugeFinding]], zenoh: dict[str, Any], header: list[str]) -> str:
    """The whole config file; ``header`` lines become its opening comment."""
    lines = [f"# {line}" if line else "#" for line in header]
    lines += [f"site: {site}", "zenoh:"]
    lines += [f"  {key}: {json.dumps(value) if isinstance(value, list) else _scalar(value)}" for key, value in zenoh.items()]
    lines.append("cameras:")
    for camera in cameras:
        lines.append(f"  - id: {camera.camera}")
        lines.append(f"    source: {_flow(camera.source)}")
        if camera.note:
            lines.append(f"    # NOTE: {_comment(camera.note)}")
    found = [g for camera in cameras for g in gauges.get(camera.camera, [])]
    lines.append("gauges:" if found else "gauges: []")
    for camera in cameras:
        mine, left_out = gauges.get(camera.camera, []), dropped.get(camera.camera, [])
        frames = len(camera.frames)
        todo = sum(g.todo is not None for g in mine)
        lines.append(f"  # {camera.camera}: {len(mine)} gauge(s) found on {frames} frame(s)"
                     + (f", {todo} with a TODO" if todo else ""))
        for box in left_out:
            roi = ", ".join(f"{v:.0f}" for v in box.box)
            lines.append(f"  # left out: a box at [{roi}] found on only {box.seen} of {frames} frame(s)")
        for gauge in mine:
            lines.extend(gauge_block(gauge))
    return "\n".join(lines) + "\n"
