"""Ground truth of synthetic renders, and its JSON-lines schema.

Every render comes with one record per image (``labels.jsonl`` holds one per line; an MCAP
recording carries the same record on ``/<camera>/truth``). All coordinates are pixels of that image
in the project's convention (``gauged.types``: x right, y down, origin at the top-left corner of the
top-left pixel); points may lie outside the image when a gauge is cut by the frame edge. Angles are
image angles in radians (``atan2(dy, dx)``, positive = clockwise on screen). Floats are rounded to
1/1000 px.

Image record::

    {"image": "000123.jpg" | null, "width": W, "height": H, "stamp_ns": int | null,
     "camera": str | null, "render_scale": float, "gauges": [Gauge, ...]}

A notch is ``visible`` when the pixel under it shows this gauge's own dial: not an occluder, not
another gauge in front, not outside the frame (the needle does not hide a notch: it is part of the
dial). ``labelled`` says whether a number is printed at the notch. Records written before
visibility existed lack the ``visible`` keys; readers take them as visible.

``render_scale`` is the share of the image's resolution the camera captured: 1.0, or for a crop
rendered small and upsampled (a far gauge) its render size over its output size (0.12-0.6). A
number 10 px tall in an image of render scale 0.25 was captured 2.5 px tall: that, not its size in
the image, is what any reader can resolve.

Gauge::

    {"gauge": str,                     # id: "g0", "g1", ... or the gauge id of a recording
     "box": [x0, y0, x1, y1],          # whole visible gauge front and case, clipped to the image
     "box_unclipped": [x0, y0, x1, y1],
     "face_box": [x0, y0, x1, y1],     # box of the face ellipse (unclipped)
     "face": Ellipse,                  # image of the face circle (radius 1 face unit)
     "bezel": Ellipse,                 # image of the outer rim of the bezel
     "pivot": [x, y],                  # image of the needle pivot (NOT the centre of the ellipses)
     "visible_fraction": float,        # share of the gauge silhouette not hidden by occluders/frame
     "diameter_px": float,             # face diameter of a frontal view at the same distance
     "needle": {"tip": [x, y], "pivot": [x, y], "angle": rad,   # angle of pivot -> tip
                "polygon": [[x, y], ...],                        # pointing part
                "counterweight": [[[x, y], ...], ...],           # polygons (a ring is outer + hole)
                "shape": str, "color": [b, g, r], "at_stop": bool},
     "value": float, "unit": str,      # the true reading on the primary scale (scales[0]) ...
     "min": float, "max": float,       # ... and that scale's ends (the keys of gauged's older truth)
     "scales": [Scale, ...],           # primary first, then an inner secondary scale if any
     "texts": [Text, ...]}             # brand, serial, class, standard, other

Scale::

    {"role": "primary" | "secondary", "min": float, "max": float, "unit": str, "unit_text": str,
     "ellipse": Ellipse,               # image of the circle through the major notch centres
     "start": [x, y], "end": [x, y],   # notch points of min and max (whatever the direction: on a
                                       # counter-clockwise scale "start" is the clockwise-last end)
     "majors": [{"value": v, "point": [x, y], "labelled": bool, "visible": bool}, ...],   # every major notch
     "minors": [{"point": [x, y], "visible": bool}, ...],   # every minor notch (none when the style has none)
     "start_visible": bool, "end_visible": bool,
     "numbers": [Text, ...],           # every printed number, with "value"
     "unit_label": Text | null,
     "reading": float,                 # the needle's value on this scale
     "sweep_deg": float,               # angle from min to max on the dial (frontal), positive
     "direction": "cw" | "ccw"}        # which way values rise on the dial (the secondary follows the primary)

Text::  {"text": str, "kind": str, "box": [x0, y0, x1, y1], "quad": [[x, y] x 4], "value": float | null}
        (quad corners in reading order: top-left, top-right, bottom-right, bottom-left)
Ellipse:: {"cx", "cy", "a", "b", "theta"} as ``gauged.types.Ellipse`` (a >= b, theta in [0, pi)).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from gauged.synth.dial import PlacedText, outer_radius, scale_marks, tick_extent
from gauged.synth.needle import NeedleGeometry
from gauged.synth.params import GaugeParams
from gauged.synth.projection import apply_homography, points_box, project_circle
from gauged.types import Box, Ellipse


def _r(x: float) -> float:
    return round(float(x), 3)


def _pt(p: np.ndarray) -> list[float]:
    return [_r(p[0]), _r(p[1])]


def _pts(p: np.ndarray) -> list[list[float]]:
    return [[_r(x), _r(y)] for x, y in np.asarray(p).reshape(-1, 2)]


def _box(b: Box) -> list[float]:
    return [_r(v) for v in b]


def _ellipse(e: Ellipse) -> dict[str, float]:
    return {"cx": _r(e.cx), "cy": _r(e.cy), "a": _r(e.a), "b": _r(e.b), "theta": round(e.theta, 6)}


def _value(v: float) -> float:
    return float(f"{v:.7g}")


def clip_box(b: Box, width: int, height: int) -> Box:
    return (min(max(b[0], 0.0), width), min(max(b[1], 0.0), height), min(max(b[2], 0.0), width), min(max(b[3], 0.0), height))


@dataclass
class GaugeTruth:
    """Ground truth of one gauge in one image; :meth:`to_dict` gives the documented schema."""

    data: dict[str, Any] = field(default_factory=dict)

    @property
    def value(self) -> float:
        """The true reading on the primary scale."""
        return self.data["value"]

    def to_dict(self) -> dict[str, Any]:
        return self.data


def _text_truth(t: PlacedText, h: np.ndarray) -> dict[str, Any]:
    quad = apply_homography(h, t.quad)
    return {"text": t.text, "kind": t.kind, "box": _box(points_box(quad)), "quad": _pts(quad),
            "value": None if t.value is None else _value(t.value)}


def gauge_truth(params: GaugeParams, texts: tuple[PlacedText, ...], needle: NeedleGeometry, h: np.ndarray,
                body_points: np.ndarray, image_size: tuple[int, int], gauge_id: str,
                visible_fraction: float, diameter_px: float, front: np.ndarray | None = None,
                front_scale: float = 1.0) -> GaugeTruth:
    """Project the face-unit geometry of a gauge through ``h`` (face units -> image px).

    ``body_points`` (N, 2) are image points of the visible case outline (for the box);
    ``image_size`` is (width, height). ``front`` (rows, cols) bool is where this gauge's dial is
    seen, sampled at image point times ``front_scale`` (its resolution over the image's); None
    marks every notch inside the image visible.
    """
    width, height = image_size
    face = project_circle(h, 0.0, 0.0, 1.0)
    rb = outer_radius(params)
    bezel = project_circle(h, 0.0, 0.0, rb)
    rim = apply_homography(h, np.column_stack([rb * np.cos(np.linspace(0, 2 * math.pi, 73)),
                                               rb * np.sin(np.linspace(0, 2 * math.pi, 73))]))
    full = points_box(np.vstack([rim, body_points]) if len(body_points) else rim)
    pivot = apply_homography(h, np.zeros((1, 2)))[0]
    tip = apply_homography(h, needle.tip[None])[0]
    angle = params.needle_angle
    scales = []
    for i, s in enumerate(params.scales):
        _, majors, minors = scale_marks(s)
        labels = set(np.round(np.asarray(scale_marks(s)[0]), 9).tolist())
        ang = np.array([s.angle_of(float(v)) for v in majors])
        pts = apply_homography(h, s.radius * np.column_stack([np.cos(ang), np.sin(ang)]))
        minor_ang = np.array([s.angle_of(float(v)) for v in minors])
        minor_r = sum(tick_extent(s, major=False)) / 2  # a minor notch's middle: shorter, it may sit off the radius
        minor_pts = apply_homography(h, minor_r * np.column_stack([np.cos(minor_ang), np.sin(minor_ang)])).reshape(-1, 2)
        ends = apply_homography(h, s.radius * np.array([[math.cos(s.start_angle), math.sin(s.start_angle)],
                                                        [math.cos(s.end_angle), math.sin(s.end_angle)]]))
        unit_label = [t for t in texts if t.kind == "unit" and t.scale == i]
        seen = _visible(np.vstack([pts.reshape(-1, 2), ends]), front, front_scale, image_size)
        minor_seen = _visible(minor_pts, front, front_scale, image_size) if len(minor_pts) else []
        scales.append({
            "role": s.role, "min": _value(s.min), "max": _value(s.max), "unit": s.unit, "unit_text": s.unit_text,
            "ellipse": _ellipse(project_circle(h, 0.0, 0.0, s.radius)),
            "start": _pt(ends[0]), "end": _pt(ends[1]),
            "start_visible": bool(seen[-2]), "end_visible": bool(seen[-1]),
            "majors": [{"value": _value(v), "point": _pt(p), "labelled": round(float(v), 9) in labels,
                        "visible": bool(seen[k])} for k, (v, p) in enumerate(zip(majors, pts))],
            "minors": [{"point": _pt(p), "visible": bool(minor_seen[k])} for k, p in enumerate(minor_pts)],
            "numbers": [_text_truth(t, h) for t in texts if t.kind == "number" and t.scale == i],
            "unit_label": _text_truth(unit_label[0], h) if unit_label else None,
            "reading": _value(s.value_at(angle)),
            "sweep_deg": round(math.degrees(s.sweep), 4),
            "direction": s.direction,
        })
    data = {
        "gauge": gauge_id,
        "box": _box(clip_box(full, width, height)),
        "box_unclipped": _box(full),
        "face_box": _box(points_box(face.point_at(np.linspace(0, 2 * math.pi, 90)))),
        "face": _ellipse(face),
        "bezel": _ellipse(bezel),
        "pivot": _pt(pivot),
        "visible_fraction": round(float(visible_fraction), 4),
        "diameter_px": _r(diameter_px),
        "needle": {
            "tip": _pt(tip), "pivot": _pt(pivot),
            "angle": round(math.atan2(tip[1] - pivot[1], tip[0] - pivot[0]), 7),
            "polygon": _pts(apply_homography(h, needle.pointing)),
            "counterweight": [_pts(apply_homography(h, q)) for q in needle.counterweight],
            "shape": params.needle.shape, "color": list(params.needle.color), "at_stop": params.at_stop,
        },
        "value": _value(params.value),
        "unit": params.primary.unit,
        "min": _value(params.primary.min),
        "max": _value(params.primary.max),
        "scales": scales,
        "texts": [_text_truth(t, h) for t in texts if t.kind not in ("number", "unit")],
    }
    return GaugeTruth(data)


def _visible(points: np.ndarray, front: np.ndarray | None, front_scale: float,
             image_size: tuple[int, int]) -> np.ndarray:
    """Per (N, 2) image point: inside the image and, with ``front``, on this gauge's seen dial."""
    width, height = image_size
    inside = (points[:, 0] >= 0) & (points[:, 0] < width) & (points[:, 1] >= 0) & (points[:, 1] < height)
    if front is None:
        return inside
    cols = np.clip((points[:, 0] * front_scale).astype(int), 0, front.shape[1] - 1)
    rows = np.clip((points[:, 1] * front_scale).astype(int), 0, front.shape[0] - 1)
    return inside & front[rows, cols]


def image_record(gauges: list[GaugeTruth], width: int, height: int, *, image: str | None = None,
                 stamp_ns: int | None = None, camera: str | None = None, render_scale: float = 1.0) -> dict[str, Any]:
    """The per-image record of the schema above."""
    return {"image": image, "width": width, "height": height, "stamp_ns": stamp_ns, "camera": camera,
            "render_scale": round(float(render_scale), 4), "gauges": [g.to_dict() for g in gauges]}
