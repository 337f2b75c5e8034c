"""A compact procedural dial renderer for training the models, with exact keypoint labels.

A dial is drawn frontal on a square canvas (face, bezel, coloured bands, major/minor ticks, numbers,
unit and distractor text, needle with counterweight and hub), then warped by a random homography
(tilt up to 60 degrees, in-plane rotation, scale, shift) into the output; every label point goes
through the same homography, so labels are exact in the project's pixel convention.

Channels labelled per crop (see :data:`gauged.reader.stages.keypoints.CROP_CHANNELS`): ``start``/``end``
(the end notches of the scale), ``major`` (every major notch, on the scale circle), ``tip`` and
``pivot`` of the needle, ``numbers`` (centres of the scale numbers), and the needle mask (the
pointing part, pivot to tip, as the real needle-polygons labels are).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import cv2
import numpy as np

RANGES = ((0, 1), (0, 1.6), (0, 2.5), (0, 4), (0, 6), (0, 10), (0, 16), (0, 25), (0, 40), (0, 60), (0, 100),
          (0, 160), (0, 250), (0, 400), (-1, 0), (-1, 3), (-30, 50), (0, 0.25), (-1, 1.5), (0, 600), (0, 300),
          (-40, 140), (0, 200), (0, 50), (0, 6000))
UNITS = ("bar", "mbar", "kPa", "MPa", "psi", "kg/cm2", "inHg", "C", "F", "%")
DISTRACTORS = ("EN 837-1", "CL 1.6", "1.6", "WIKA", "SN 48213", "MADE IN", "Class 1.0", "NS 100", "G1/2", "DN 63")
FONTS = (cv2.FONT_HERSHEY_SIMPLEX, cv2.FONT_HERSHEY_DUPLEX, cv2.FONT_HERSHEY_COMPLEX, cv2.FONT_HERSHEY_TRIPLEX,
         cv2.FONT_HERSHEY_PLAIN)
CANVAS = 512


def nice_step(span: float, rng: np.random.Generator) -> float:
    """A major step a real gauge would use: 1, 2, 2.5 or 5 x 10^k giving 4 to 11 numbers."""
    options = []
    for k in range(-3, 5):
        for m in (1, 2, 2.5, 5):
            step = m * 10.0**k
            count = span / step
            if 4 <= count <= 10 and abs(count - round(count)) < 1e-6:
                options.append(step)
    return float(rng.choice(options)) if options else span / 5


def fmt(value: float) -> str:
    text = f"{value:.3f}".rstrip("0").rstrip(".")
    return "0" if text in ("-0", "") else text


@dataclass
class DialLabels:
    """Labels in output pixels: points per channel, needle mask, reading."""

    points: dict[str, np.ndarray]
    needle: np.ndarray  # (S, S) uint8 {0, 1}
    value: float
    min_value: float
    max_value: float
    unit: str
    face_box: tuple[float, float, float, float]


def _colour(rng: np.random.Generator, dark: bool) -> tuple[int, int, int]:
    if dark:
        return tuple(int(v) for v in rng.integers(0, 60, 3))
    base = int(rng.integers(200, 256))
    tint = rng.integers(-25, 10, 3)
    return tuple(int(np.clip(base + t, 0, 255)) for t in tint)


def _background(size: int, rng: np.random.Generator) -> np.ndarray:
    grey = rng.uniform(20, 235)
    colour = (grey + rng.normal(0, 25, 3)).astype(np.float32)  # mostly neutral: metal, concrete, walls
    noise = cv2.resize(rng.normal(0, 1, (8, 8, 3)).astype(np.float32), (size, size), interpolation=cv2.INTER_CUBIC)
    image = colour[None, None, :] + noise * rng.uniform(10, 60)
    for _ in range(int(rng.integers(0, 4))):  # pipes, brackets, clutter
        p = rng.integers(0, size, 4)
        cv2.line(image, (int(p[0]), int(p[1])), (int(p[2]), int(p[3])), tuple(float(v) for v in rng.integers(0, 255, 3)),
                 int(rng.integers(4, size // 6)))
    return image.clip(0, 255).astype(np.uint8)


def _point(cx: float, cy: float, radius: float, angle: float) -> tuple[float, float]:
    return (cx + radius * math.cos(angle), cy + radius * math.sin(angle))


def _p16(point) -> tuple[int, int]:
    return (int(round((point[0] - 0.5) * 16)), int(round((point[1] - 0.5) * 16)))


def draw_dial(rng: np.random.Generator, value: float | None = None, scale_range: tuple[float, float] | None = None,
              unit: str | None = None) -> tuple[np.ndarray, np.ndarray, dict[str, np.ndarray], np.ndarray, dict]:
    """Frontal dial on a CANVAS² image: (image, alpha mask of the dial, points, needle mask, facts).

    The same generator state always draws the same dial; ``value``, ``scale_range`` and ``unit``, when
    given, replace the random ones without changing any other random choice (so a sequence can move
    the needle of one fixed dial).
    """
    s = CANVAS
    cx = cy = s / 2
    face_r = s * 0.42
    bezel = face_r * rng.uniform(0.03, 0.14)
    dark = rng.random() < 0.2
    face = _colour(rng, dark) if rng.random() < 0.9 else tuple(int(v) for v in rng.integers(80, 230, 3))
    ink = (235, 235, 235) if dark else tuple(int(v) for v in rng.integers(0, 50, 3))
    image = np.zeros((s, s, 3), np.uint8)
    alpha = np.zeros((s, s), np.uint8)
    cv2.circle(alpha, _p16((cx, cy)), int((face_r + bezel) * 16), 255, -1, cv2.LINE_AA, 4)
    grey = int(rng.integers(30, 230))  # chrome, steel, black plastic; now and then a painted bezel
    bezel_colour = ((grey,) * 3 if rng.random() < 0.75 else tuple(int(v) for v in rng.integers(40, 230, 3)))
    cv2.circle(image, _p16((cx, cy)), int((face_r + bezel) * 16), bezel_colour, -1, cv2.LINE_AA, 4)
    cv2.circle(image, _p16((cx, cy)), int(face_r * 16), face, -1, cv2.LINE_AA, 4)
    lo, hi = RANGES[int(rng.integers(len(RANGES)))]
    if scale_range is not None:
        lo, hi = scale_range
    step = nice_step(hi - lo, rng)
    span = math.radians(rng.choice([270, 270, 270, 240, 180, 300, 90 + 240 * rng.random()]))
    start = math.pi / 2 + (2 * math.pi - span) / 2  # gap centred at the bottom; the warp rotates it
    scale_r = face_r * rng.uniform(0.62, 0.92)
    tick_len = face_r * rng.uniform(0.07, 0.14)
    inward = rng.random() < 0.8
    majors = np.arange(0, round((hi - lo) / step) + 1) * step + lo
    angle_of = lambda v: start + span * (v - lo) / (hi - lo)  # noqa: E731
    # coloured bands along the scale
    for _ in range(int(rng.integers(0, 3))):
        a0 = rng.uniform(0, 0.8)
        a1 = min(1.0, a0 + rng.uniform(0.1, 0.4))
        colour = [(40, 160, 40), (40, 40, 210), (30, 200, 230)][int(rng.integers(3))]
        r = scale_r - tick_len * 0.3 if inward else scale_r + tick_len * 0.3
        cv2.ellipse(image, _p16((cx, cy)), (int(r * 16), int(r * 16)), 0, math.degrees(start + span * a0),
                    math.degrees(start + span * a1), colour, max(2, int(tick_len * 0.5)), cv2.LINE_AA, 4)
    thick = max(1, int(face_r * rng.uniform(0.008, 0.025)))
    minor_div = int(rng.choice([2, 4, 5, 10]))
    style = rng.choice(["line", "line", "line", "wedge", "dot"])
    for k, v in enumerate(np.linspace(lo, hi, (len(majors) - 1) * minor_div + 1)):
        a = angle_of(v)
        major = k % minor_div == 0
        length = tick_len if major else tick_len * 0.5
        r0, r1 = (scale_r, scale_r - length) if inward else (scale_r, scale_r + length)
        if style == "dot" and major:
            cv2.circle(image, _p16(_point(cx, cy, (r0 + r1) / 2, a)), int(length * 0.3 * 16), ink, -1, cv2.LINE_AA, 4)
        elif style == "wedge" and major:
            w = length * 0.15
            tip = _point(cx, cy, r1, a)
            base0 = _point(cx, cy, r0, a - w / r0)
            base1 = _point(cx, cy, r0, a + w / r0)
            cv2.fillConvexPoly(image, np.array([_p16(tip), _p16(base0), _p16(base1)]), ink, cv2.LINE_AA, 4)
        else:
            cv2.line(image, _p16(_point(cx, cy, r0, a)), _p16(_point(cx, cy, r1, a)), ink,
                     thick if major else max(1, thick // 2), cv2.LINE_AA, 4)
    if rng.random() < 0.5:  # the scale's circle line
        cv2.circle(image, _p16((cx, cy)), int(scale_r * 16), ink, max(1, thick // 2), cv2.LINE_AA, 4)
    font = int(rng.choice(FONTS))
    text_h = face_r * rng.uniform(0.07, 0.12)
    font_scale = cv2.getFontScaleFromHeight(font, max(6, int(text_h)), 1)
    text_thick = max(1, int(text_h / rng.uniform(6, 12)))
    number_r = (scale_r - tick_len - text_h * 1.1) if inward else (scale_r - text_h * 1.0)
    radial_text = rng.random() < 0.25
    number_centres = []
    for v in majors:
        text = fmt(v)
        (w, h), _ = cv2.getTextSize(text, font, font_scale, text_thick)
        centre = _point(cx, cy, number_r - (w / 2 if not radial_text else 0) * 0.3, angle_of(v))
        number_centres.append(centre)
        _put_text(image, text, centre, font, font_scale, text_thick, ink,
                  math.degrees(angle_of(v)) + 90 if radial_text else 0.0)
    drawn_unit = UNITS[int(rng.integers(len(UNITS)))]
    unit = unit or drawn_unit
    _put_text(image, unit, (cx, cy + face_r * rng.uniform(0.25, 0.45)), font, font_scale * 1.1, text_thick, ink, 0)
    for _ in range(int(rng.integers(0, 3))):
        _put_text(image, DISTRACTORS[int(rng.integers(len(DISTRACTORS)))],
                  (cx + face_r * rng.uniform(-0.3, 0.3), cy + face_r * rng.uniform(-0.45, 0.55)), font,
                  font_scale * rng.uniform(0.4, 0.8), max(1, text_thick // 2), ink, 0)
    # needle
    at_rest, rest_offset, drawn = rng.random() < 0.12, rng.uniform(0, 0.05), float(rng.uniform(lo, hi))
    if value is not None:
        needle_angle = angle_of(min(max(value, lo), hi))
    elif at_rest:
        value, needle_angle = lo, start - rest_offset  # resting against the stop pin
    else:
        value, needle_angle = drawn, angle_of(drawn)
    needle_colour = (30, 30, 210) if rng.random() < 0.35 else ((240, 240, 240) if dark else (20, 20, 20))
    length = scale_r * rng.uniform(0.8, 1.02)
    tail = face_r * rng.uniform(0.0, 0.3)
    width = face_r * rng.uniform(0.015, 0.05)
    tip = _point(cx, cy, length, needle_angle)
    nx, ny = -math.sin(needle_angle), math.cos(needle_angle)
    base = [(cx + nx * width, cy + ny * width), (cx - nx * width, cy - ny * width)]
    tip_w = width * rng.uniform(0.05, 0.5)
    tip_pts = [(tip[0] - nx * tip_w, tip[1] - ny * tip_w), (tip[0] + nx * tip_w, tip[1] + ny * tip_w)]
    pointing = np.array([base[0], tip_pts[1], tip_pts[0], base[1]])
    needle_mask = np.zeros((s, s), np.uint8)
    cv2.fillConvexPoly(needle_mask, np.array([_p16(p) for p in pointing]), 1, cv2.LINE_8, 4)
    shadow = np.array([_p16((x + face_r * 0.02, y + face_r * 0.02)) for x, y in pointing])
    overlay = image.copy()
    cv2.fillConvexPoly(overlay, shadow, (0, 0, 0), cv2.LINE_AA, 4)
    image = cv2.addWeighted(overlay, 0.25, image, 0.75, 0)
    cv2.fillConvexPoly(image, np.array([_p16(p) for p in pointing]), needle_colour, cv2.LINE_AA, 4)
    if tail > 0:
        back = _point(cx, cy, tail, needle_angle + math.pi)
        cv2.line(image, _p16((cx, cy)), _p16(back), needle_colour, max(1, int(width * 1.6)), cv2.LINE_AA, 4)
    hub = face_r * rng.uniform(0.03, 0.09)
    cv2.circle(image, _p16((cx, cy)), int(hub * 16), needle_colour if rng.random() < 0.6 else bezel_colour, -1,
               cv2.LINE_AA, 4)
    # glass glare
    if rng.random() < 0.5:
        glare = np.zeros_like(image)
        centre = _point(cx, cy, face_r * rng.uniform(0.2, 0.6), rng.uniform(0, 2 * math.pi))
        axes = (int(face_r * rng.uniform(0.2, 0.6) * 16), int(face_r * rng.uniform(0.05, 0.25) * 16))
        cv2.ellipse(glare, _p16(centre), axes, rng.uniform(0, 180), 0, 360, (255, 255, 255), -1, cv2.LINE_AA, 4)
        glare = cv2.GaussianBlur(glare, (0, 0), face_r * 0.05)
        image = cv2.addWeighted(image, 1.0, glare, rng.uniform(0.2, 0.7), 0)
    points = {
        "start": np.array([_point(cx, cy, scale_r, start)]),
        "end": np.array([_point(cx, cy, scale_r, start + span)]),
        "major": np.array([_point(cx, cy, scale_r, angle_of(v)) for v in majors]),
        "tip": np.array([tip]),
        "pivot": np.array([(cx, cy)]),
        "numbers": np.array(number_centres),
        "face": np.array([_point(cx, cy, face_r + bezel, a) for a in np.linspace(0, 2 * math.pi, 32, endpoint=False)]),
    }
    facts = {"value": value, "min": lo, "max": hi, "unit": unit}
    return image, alpha, points, needle_mask, facts


def _put_text(image, text, centre, font, font_scale, thickness, colour, angle_deg) -> None:
    (w, h), baseline = cv2.getTextSize(text, font, font_scale, thickness)
    if abs(angle_deg) < 1e-6:
        cv2.putText(image, text, (int(centre[0] - w / 2), int(centre[1] + h / 2)), font, font_scale, colour, thickness,
                    cv2.LINE_AA)
        return
    pad = 4
    patch = np.zeros((h + baseline + 2 * pad, w + 2 * pad), np.uint8)
    cv2.putText(patch, text, (pad, pad + h), font, font_scale, 255, thickness, cv2.LINE_AA)
    side = int(math.hypot(*patch.shape)) + 2
    canvas = np.zeros((side, side), np.uint8)
    y0, x0 = (side - patch.shape[0]) // 2, (side - patch.shape[1]) // 2
    canvas[y0:y0 + patch.shape[0], x0:x0 + patch.shape[1]] = patch
    rot = cv2.getRotationMatrix2D((side / 2, side / 2), -angle_deg, 1.0)
    canvas = cv2.warpAffine(canvas, rot, (side, side))
    x, y = int(centre[0] - side / 2), int(centre[1] - side / 2)
    H, W = image.shape[:2]
    xs0, ys0, xs1, ys1 = max(0, x), max(0, y), min(W, x + side), min(H, y + side)
    if xs0 >= xs1 or ys0 >= ys1:
        return
    a = canvas[ys0 - y:ys1 - y, xs0 - x:xs1 - x].astype(np.float32)[..., None] / 255
    region = image[ys0:ys1, xs0:xs1].astype(np.float32)
    image[ys0:ys1, xs0:xs1] = (region * (1 - a) + np.array(colour, np.float32) * a).astype(np.uint8)


def random_homography(rng: np.random.Generator, out_size: int, fill: float) -> np.ndarray:
    """Canvas -> output homography: tilt (<= 60 deg), rotation, scale so the dial fills ``fill`` of the output."""
    tilt = math.radians(min(60.0, abs(rng.normal(0, 22))))
    direction = rng.uniform(0, 2 * math.pi)
    rotation = rng.normal(0, 0.35) if rng.random() < 0.8 else rng.uniform(-math.pi, math.pi)
    f = CANVAS * rng.uniform(1.2, 3.0)  # focal length: stronger perspective for short ones
    c = CANVAS / 2
    # Rotate the dial plane about an axis in the plane, then project with a pinhole at distance f.
    axis = np.array([math.cos(direction), math.sin(direction), 0.0])
    k = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    tilt_r = np.eye(3) + math.sin(tilt) * k + (1 - math.cos(tilt)) * k @ k
    spin = np.array([[math.cos(rotation), -math.sin(rotation), 0], [math.sin(rotation), math.cos(rotation), 0], [0, 0, 1]])
    r = tilt_r @ spin
    # plane point (x - c, y - c, 0) -> camera (R p + (0, 0, f)) -> image f * X/Z + c
    h = np.array([[f, 0, c], [0, f, c], [0, 0, 1]]) @ np.column_stack([r[:, 0], r[:, 1], [0, 0, f]]) \
        @ np.array([[1, 0, -c], [0, 1, -c], [0, 0, 1]])
    corners = _apply(h, np.array([[c + CANVAS * 0.47 * math.cos(a), c + CANVAS * 0.47 * math.sin(a)]
                                  for a in np.linspace(0, 2 * math.pi, 24, endpoint=False)]))
    lo, hi = corners.min(axis=0), corners.max(axis=0)
    scale = fill * out_size / max(hi - lo)
    centre = (lo + hi) / 2
    shift = rng.uniform(-0.06, 0.06, 2) * out_size
    fit = np.array([[scale, 0, out_size / 2 - scale * centre[0] + shift[0]],
                    [0, scale, out_size / 2 - scale * centre[1] + shift[1]], [0, 0, 1]])
    return fit @ h


def _apply(h: np.ndarray, points: np.ndarray) -> np.ndarray:
    pts = np.column_stack([points, np.ones(len(points))]) @ h.T
    return pts[:, :2] / pts[:, 2:3]


def _warp(image: np.ndarray, h: np.ndarray, size: int, nearest: bool = False) -> np.ndarray:
    # Our coordinates put pixel centres at +0.5; cv2 at integers: conjugate by the half-pixel shift.
    half = np.array([[1, 0, 0.5], [0, 1, 0.5], [0, 0, 1]])
    m = np.linalg.inv(half) @ h @ half
    flags = cv2.INTER_NEAREST if nearest else cv2.INTER_LINEAR
    return cv2.warpPerspective(image, m, (size, size), flags=flags, borderMode=cv2.BORDER_CONSTANT)


def camera_effects(image: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    out = image.astype(np.float32)
    out = out * rng.uniform(0.45, 1.25) + rng.uniform(-25, 25)
    out *= rng.uniform(0.85, 1.15, 3)[None, None, :]
    if rng.random() < 0.5:
        h, w = out.shape[:2]
        yy, xx = np.mgrid[0:h, 0:w]
        r2 = ((xx - w / 2) ** 2 + (yy - h / 2) ** 2) / (0.5 * max(h, w)) ** 2
        out *= (1 - rng.uniform(0.1, 0.5) * r2)[..., None]
    out = out.clip(0, 255).astype(np.uint8)
    roll = rng.random()
    if roll < 0.25:
        k = int(rng.integers(3, 9))
        kernel = np.zeros((k, k), np.float32)
        kernel[k // 2, :] = 1 / k
        kernel = cv2.warpAffine(kernel, cv2.getRotationMatrix2D((k / 2 - 0.5, k / 2 - 0.5), rng.uniform(0, 180), 1), (k, k))
        out = cv2.filter2D(out, -1, kernel / max(kernel.sum(), 1e-6))
    elif roll < 0.5:
        out = cv2.GaussianBlur(out, (0, 0), rng.uniform(0.5, 2.0))
    out = (out.astype(np.float32) + rng.normal(0, rng.uniform(0, 10), out.shape)).clip(0, 255).astype(np.uint8)
    if rng.random() < 0.6:
        ok, buf = cv2.imencode(".jpg", out, [cv2.IMWRITE_JPEG_QUALITY, int(rng.integers(30, 95))])
        out = cv2.imdecode(buf, cv2.IMREAD_COLOR)
    return out


def render_crop(seed: int, size: int = 224) -> tuple[np.ndarray, DialLabels]:
    """A gauge crop as the detector would cut it (dial filling 75-98% of it), with its labels."""
    rng = np.random.default_rng(seed)
    dial, alpha, points, needle, facts = draw_dial(rng)
    supersample = 2
    big = size * supersample
    h = random_homography(rng, big, rng.uniform(0.75, 0.98))
    warped = _warp(dial, h, big)
    mask = _warp(alpha, h, big).astype(np.float32)[..., None] / 255
    background = _background(big, rng)
    composed = (warped * mask + background * (1 - mask)).astype(np.uint8)
    image = cv2.resize(composed, (size, size), interpolation=cv2.INTER_AREA)
    down = np.diag([1 / supersample, 1 / supersample, 1.0])
    h_out = down @ h
    needle_out = _warp(needle, h_out, size, nearest=True)
    labels = {name: _apply(h_out, pts) for name, pts in points.items()}
    face = labels.pop("face")
    box = (float(face[:, 0].min()), float(face[:, 1].min()), float(face[:, 0].max()), float(face[:, 1].max()))
    image = camera_effects(image, rng)
    return image, DialLabels(labels, needle_out, facts["value"], facts["min"], facts["max"], facts["unit"], box)


def render_scene(seed: int, width: int = 1280, height: int = 720, max_gauges: int = 4
                 ) -> tuple[np.ndarray, list[tuple[float, float, float, float]]]:
    """A full camera frame with 0-``max_gauges`` dials on clutter; returns (image, dial boxes)."""
    rng = np.random.default_rng(seed)
    scene = cv2.resize(_background(256, rng), (width, height), interpolation=cv2.INTER_LINEAR).astype(np.float32)
    for _ in range(int(rng.integers(2, 8))):  # pipes, posts, panels: long straight clutter
        p = rng.integers(0, max(width, height), 4)
        colour = tuple(float(v) for v in rng.integers(20, 230, 3))
        cv2.line(scene, (int(p[0]), int(p[1])), (int(p[2]), int(p[3])), colour, int(rng.integers(5, 60)))
    boxes = []
    count = int(rng.choice([0, 1, 1, 2, 2, 3, 4][: max_gauges + 3]))
    for _ in range(count):
        diameter = float(np.exp(rng.uniform(np.log(40), np.log(min(height, 700)))))
        dial, alpha, points, _, _ = draw_dial(rng)
        h = random_homography(rng, int(diameter), 1.0)
        x = rng.uniform(-0.1 * diameter, width - 0.9 * diameter)
        y = rng.uniform(-0.1 * diameter, height - 0.9 * diameter)
        h = np.array([[1, 0, x], [0, 1, y], [0, 0, 1]]) @ h
        face = _apply(h, points["face"])
        box = (max(0.0, face[:, 0].min()), max(0.0, face[:, 1].min()), min(width, face[:, 0].max()),
               min(height, face[:, 1].max()))
        if any(_overlap(box, b) > 0.3 for b in boxes) or box[2] - box[0] < 12 or box[3] - box[1] < 12:
            continue
        half = np.array([[1, 0, 0.5], [0, 1, 0.5], [0, 0, 1]])
        m = np.linalg.inv(half) @ h @ half
        warped = cv2.warpPerspective(dial, m, (width, height)).astype(np.float32)
        mask = cv2.warpPerspective(alpha, m, (width, height)).astype(np.float32)[..., None] / 255
        scene = warped * mask + scene * (1 - mask)
        boxes.append(box)
    if rng.random() < 0.3 and boxes:  # something in front of a dial
        x0, y0, x1, y1 = boxes[int(rng.integers(len(boxes)))]
        p = (int(rng.uniform(x0, x1)), int(rng.uniform(y0 - 50, y1 + 50)))
        cv2.line(scene, p, (p[0] + int(rng.uniform(-40, 40)), p[1] + 300), tuple(float(v) for v in rng.integers(20, 200, 3)),
                 int(max(4, 0.15 * (x1 - x0))))
    return camera_effects(scene.clip(0, 255).astype(np.uint8), rng), boxes


def _overlap(a, b) -> float:
    from gauged.geometry.boxes import box_iou

    return box_iou(a, b)
