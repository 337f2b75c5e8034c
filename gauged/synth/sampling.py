"""Draw random :class:`~gauged.synth.params.GaugeParams` from a ``numpy.random.Generator``.

The distributions follow what the real photos in ``shared/datasets`` show: mostly white or cream
faces with black print, a fair share of black faces with white print, chrome and black bezels,
270-degree scales centred on 12 o'clock, tapered black or red needles; and a tail of less common
looks (quadrant scales, dual bar/psi scales, dots and wedges, coloured zones) so learned models do
not over-fit the common case. ``clean=True`` turns off every nuisance (glass, grain, shadows) for
ground-truth tests.

Scales rise clockwise unless ``direction`` asks otherwise: ``"ccw"`` draws every gauge with values
rising counter-clockwise (mostly from :data:`~gauged.synth.ranges.CCW_RANGES`: vacuum, compound,
negative and decimal ranges), ``"mixed"`` a share :data:`CCW_SHARE` of them. A counter-clockwise
gauge is drawn as a clockwise one and then mirrored about its arc's axis (:func:`reverse_direction`),
so its layout is as plausible; the clockwise default draws exactly what it drew before directions
existed (held-out sets are keyed on seeds).
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from gauged.synth.fonts import FONT_KEYS
from gauged.synth.params import (Band, BezelParams, Color, FaceParams, GaugeParams, GlassParams, NeedleParams,
                                 ScaleParams, TextItem, TextStyle)
from gauged.synth.ranges import (CCW_RANGES, RANGES, UNIT_TEXT, RangeSpec, convert, conversions_from, decimals_of, grid,
                                 nice_division)

# (name, BGR colour, weight, dark)
FACES: tuple[tuple[str, Color, float, bool], ...] = (
    ("white", (246, 246, 246), 0.30, False), ("off-white", (232, 236, 238), 0.12, False),
    ("cream", (196, 226, 240), 0.10, False), ("ivory", (214, 236, 246), 0.06, False),
    ("black", (24, 24, 24), 0.16, True), ("charcoal", (48, 46, 44), 0.05, True),
    ("light-blue", (238, 214, 186), 0.05, False), ("yellow", (110, 214, 242), 0.03, False),
    ("pale-green", (196, 224, 200), 0.03, False), ("silver", (196, 198, 200), 0.05, False),
    ("aged", (158, 192, 208), 0.05, False),
)
INK_LIGHT: tuple[Color, ...] = ((18, 18, 18), (18, 18, 18), (30, 26, 22), (110, 40, 16), (25, 25, 150))
INK_DARK: tuple[Color, ...] = ((238, 238, 238), (238, 238, 238), (170, 230, 245), (60, 150, 250))
SECONDARY_INK: tuple[Color, ...] = ((30, 30, 200), (150, 60, 20), (20, 110, 30))
SECONDARY_INK_DARK: tuple[Color, ...] = ((60, 150, 250), (120, 220, 120), (250, 200, 130), (90, 90, 240))
BANDS: dict[str, Color] = {"red": (40, 40, 210), "green": (60, 160, 40), "yellow": (40, 200, 230)}
DIRECTIONS = ("cw", "ccw", "mixed")
CCW_SHARE = 0.3  # of the gauges of direction "mixed"
CCW_SPECIAL = 0.7  # of counter-clockwise gauges drawn from CCW_RANGES (the rest from RANGES)
SWEEPS_DEG = (270, 270, 270, 270, 270, 240, 300, 180, 90, 330, 260, 280)
_SYLLABLES = ("ma", "no", "ter", "wi", "ka", "zen", "tro", "flu", "dyn", "pre", "sa", "lo", "vik", "bar", "gau",
              "rex", "mes", "tec", "ron", "al", "hyd", "sto", "ven", "ox")


def _choice(rng: np.random.Generator, items, weights=None):
    if weights is None:
        return items[int(rng.integers(len(items)))]
    p = np.asarray(weights, float)
    return items[int(rng.choice(len(items), p=p / p.sum()))]


def brand_name(rng: np.random.Generator) -> str:
    word = "".join(_choice(rng, _SYLLABLES) for _ in range(int(rng.integers(2, 4))))
    return _choice(rng, (word.upper(), word.capitalize(), word.upper() + "®", word.capitalize() + " GmbH"))


def _text_width(text: str, size: float) -> float:
    return 0.62 * size * len(text)  # rough em-width of digits in the fonts used


def _sample_sweep(rng: np.random.Generator) -> tuple[float, float]:
    sweep = math.radians(_choice(rng, SWEEPS_DEG) if rng.random() < 0.85 else rng.uniform(90, 330))
    centre = -math.pi / 2
    if rng.random() < 0.12:
        centre = rng.uniform(-math.pi, math.pi)
    start = (centre - sweep / 2 + math.pi) % (2 * math.pi) - math.pi
    return start, start + sweep


def _sample_ticks(rng: np.random.Generator, radius_room: float) -> dict:
    major_style = _choice(rng, ("line", "wedge", "dot"), (0.8, 0.1, 0.1))
    minor_style = _choice(rng, ("line", "dot", "none"), (0.82, 0.1, 0.08))
    major_length = rng.uniform(0.06, 0.14) * radius_room
    major_width = rng.uniform(0.010, 0.028) if major_style != "dot" else rng.uniform(0.012, 0.022)
    return dict(
        tick_side=_choice(rng, ("in", "out", "centre"), (0.7, 0.15, 0.15)),
        major_style=major_style, minor_style=minor_style,
        major_length=major_length, minor_length=major_length * rng.uniform(0.35, 0.65),
        major_width=major_width, minor_width=max(0.004, major_width * rng.uniform(0.35, 0.7)),
        baseline=bool(rng.random() < 0.35), baseline_width=rng.uniform(0.004, 0.012),
    )


def _thin_minor(ticks: dict, lo: float, hi: float, radius: float, sweep: float, major: float, minor: float) -> float:
    """A minor step whose notches stay apart (>= 3 notch widths), coarsening the division as real
    dials do on short scales; turns minor notches off when even the majors are that close."""
    def gap(step: float) -> float:
        return radius * sweep * step / (hi - lo)

    for factor in (1.0, 2.0, 2.5, 5.0):
        step = minor * factor
        ratio = major / step
        if abs(ratio - round(ratio)) < 1e-6 and gap(step) >= 3.0 * ticks["minor_width"]:
            return step
    ticks["minor_style"] = "none"
    return minor


def _fit_number_size(labels: np.ndarray, decimals: int, radius: float, sweep: float, size: float) -> float:
    longest = max(len(f"{v:.{decimals}f}") for v in labels)
    spacing = radius * sweep / max(1, len(labels) - 1)
    return float(min(size, spacing / (1.25 * 0.62 * longest)))


def sample_primary_scale(rng: np.random.Generator, ink: Color, font: str, spec: RangeSpec | None = None,
                         unit: str | None = None) -> ScaleParams:
    """The outer (primary) scale: range, divisions, geometry, notch and number styles."""
    spec = spec or _choice(rng, RANGES)
    div = _choice(rng, spec.divisions)
    unit = unit or _choice(rng, spec.units)
    start, end = _sample_sweep(rng)
    numbers_out = rng.random() < 0.18
    radius = rng.uniform(0.52, 0.66) if numbers_out else rng.uniform(0.7, 0.9)
    ticks = _sample_ticks(rng, 1.0)
    wanted = rng.uniform(0.09, 0.17)
    label_step = div.label
    while True:  # a short sweep with many numbers prints every other one, as real dials do
        labels = grid(spec.min, spec.max, label_step)
        decimals = decimals_of(label_step)
        size = _fit_number_size(labels, decimals, radius * 0.8, end - start, wanted)
        span_steps = (spec.max - spec.min) / (2 * label_step)
        if size >= 0.06 or abs(span_steps - round(span_steps)) > 1e-6 or len(labels) <= 3:
            break
        label_step *= 2
    if numbers_out:  # numbers must fit between the notches and the rim
        longest = max(len(f"{v:.{decimals}f}") for v in labels)
        room = 0.96 - radius - ticks["major_length"] / 2 - 0.03
        size = min(size, room / max(1.0, 0.62 * longest * 0.75))
    size = max(size, 0.045)
    return ScaleParams(
        role="primary", min=float(spec.min), max=float(spec.max), unit=unit,
        unit_text=_choice(rng, UNIT_TEXT[unit]), start_angle=start, end_angle=end, radius=radius,
        label_step=label_step, major_step=div.major,
        minor_step=_thin_minor(ticks, spec.min, spec.max, radius, end - start, div.major, div.minor), color=ink,
        numbers=TextStyle(font, size, ink), number_side="out" if numbers_out else "in",
        number_gap=rng.uniform(0.015, 0.05), number_orientation="tangent" if rng.random() < 0.2 else "upright",
        decimals=decimals, decimal_comma=bool(rng.random() < 0.05), **ticks,
    )


def number_ring_inner(scale: ScaleParams) -> float:
    """Rough innermost radius used by a scale's notches and numbers (face units)."""
    inner_tick = scale.radius - scale.major_length / 2
    if scale.number_side == "out":
        return inner_tick
    longest = max(len(f"{v:.{scale.decimals}f}") for v in grid(scale.min, scale.max, scale.label_step))
    extent = max(scale.numbers.size * 0.75, 0.62 * scale.numbers.size * longest)
    return inner_tick - scale.number_gap - extent


def sample_secondary_scale(rng: np.random.Generator, primary: ScaleParams, font: str, dark: bool) -> ScaleParams | None:
    """An inner scale in another unit (bar and psi), or None when none fits."""
    options = conversions_from(primary.unit)
    if not options:
        return None
    unit = _choice(rng, options)
    factor, offset = convert(primary.unit, unit)
    lo, hi = sorted((factor * primary.min + offset, factor * primary.max + offset))
    div = nice_division(hi - lo, int(rng.integers(4, 9)))
    labels = grid(lo, hi, div.label)
    if len(labels) < 3:
        return None
    s_min, s_max = float(labels[0]), float(labels[-1])
    a_min = primary.angle_of((s_min - offset) / factor)
    a_max = primary.angle_of((s_max - offset) / factor)
    ticks = _sample_ticks(rng, 0.75)
    ticks["tick_side"] = _choice(rng, ("out", "in"))
    radius = number_ring_inner(primary) - 0.03 - ticks["major_length"] / 2
    if radius < 0.38:
        return None
    decimals = decimals_of(div.label)
    size = _fit_number_size(labels, decimals, radius * 0.75, abs(a_max - a_min), rng.uniform(0.06, 0.11))
    if size < 0.05:
        return None  # no room for legible numbers: real dials then print one scale only
    color = _choice(rng, SECONDARY_INK_DARK if dark else SECONDARY_INK) if rng.random() < 0.7 else primary.color
    return ScaleParams(
        role="secondary", min=s_min, max=s_max, unit=unit, unit_text=_choice(rng, UNIT_TEXT[unit]),
        start_angle=a_min, end_angle=a_max, radius=radius, label_step=div.label, major_step=div.major,
        minor_step=_thin_minor(ticks, s_min, s_max, radius, abs(a_max - a_min), div.major, div.minor), color=color,
        numbers=TextStyle(font, size, color), number_side="in",
        number_gap=rng.uniform(0.01, 0.03), number_orientation="upright", decimals=decimals, **ticks,
    )


def _bands(rng: np.random.Generator, scale: ScaleParams) -> tuple[Band, ...]:
    if rng.random() > 0.25:
        return ()
    span = scale.max - scale.min
    width = min(rng.uniform(0.025, 0.07), scale.major_length)  # within the notches: numbers stay clear
    r0 = scale.radius + scale.major_length / 2 - width if scale.tick_side != "out" else scale.radius - scale.major_length / 2
    r0 = max(0.3, r0)
    split = scale.min + span * rng.uniform(0.55, 0.85)
    bands = [Band(split, scale.max, BANDS["red"], r0, r0 + width)]
    if rng.random() < 0.6:
        bands.insert(0, Band(scale.min + span * rng.uniform(0.0, 0.3), split - span * 0.1, BANDS["green"], r0, r0 + width))
    if rng.random() < 0.3:
        bands.insert(-1, Band(split - span * 0.1, split, BANDS["yellow"], r0, r0 + width))
    return tuple(bands)


def _sample_needle(rng: np.random.Generator, primary: ScaleParams, dark: bool, clean: bool) -> NeedleParams:
    shape = _choice(rng, ("tapered", "line", "lance", "arrow"), (0.4, 0.2, 0.2, 0.2))
    width = {"tapered": rng.uniform(0.03, 0.07), "line": rng.uniform(0.012, 0.03),
             "lance": rng.uniform(0.02, 0.04), "arrow": rng.uniform(0.012, 0.025)}[shape]
    tip_width = width if shape == "line" else rng.uniform(0.004, 0.012)
    reach = primary.radius + rng.uniform(-0.5, 0.5) * primary.major_length
    if rng.random() < 0.15:
        reach = primary.radius * rng.uniform(0.7, 0.9)
    colors = INK_DARK + ((40, 60, 230),) if dark else ((18, 18, 18), (18, 18, 18), (30, 30, 200), (40, 50, 220), (90, 40, 20))
    color = _choice(rng, colors)
    hub_color = _choice(rng, (color, color, (160, 160, 165), (30, 30, 30), (70, 140, 180)))
    light = rng.uniform(0, 2 * math.pi)
    off = rng.uniform(0.015, 0.05)
    return NeedleParams(
        shape=shape, color=color, width=width, tip_radius=float(min(reach, 0.97)), tip_width=tip_width,
        counterweight=_choice(rng, ("none", "tail", "paddle", "disc", "ring"), (0.25, 0.25, 0.2, 0.2, 0.1)),
        tail_length=rng.uniform(0.12, 0.3), tail_width=rng.uniform(0.03, 0.09),
        hub_radius=rng.uniform(0.04, 0.11), hub_color=hub_color,
        hub_style=_choice(rng, ("plain", "chrome", "screw")),
        shadow_offset=(off * math.cos(light), off * math.sin(light)),
        shadow_strength=0.0 if clean else rng.uniform(0.1, 0.45), shadow_blur=rng.uniform(0.005, 0.03),
    )


def _sample_glass(rng: np.random.Generator, clean: bool) -> GlassParams:
    light = rng.uniform(0, 2 * math.pi)
    if clean:
        return GlassParams(0, (0, 0), (1, 1), 0, 0, 0, 0, 0, 0, 0, 0, light)
    on = lambda p: rng.random() < p  # noqa: E731 - local coin flip
    r, a = math.sqrt(rng.random()) * 0.7, rng.uniform(0, 2 * math.pi)
    return GlassParams(
        glare=rng.uniform(0.1, 0.7) if on(0.5) else 0.0, glare_center=(r * math.cos(a), r * math.sin(a)),
        glare_size=(rng.uniform(0.2, 0.8), rng.uniform(0.08, 0.4)), glare_angle=rng.uniform(0, math.pi),
        reflections=int(rng.integers(1, 4)) if on(0.3) else 0, dirt=rng.uniform(0.05, 0.35) if on(0.3) else 0.0,
        specks=int(rng.integers(5, 60)) if on(0.3) else 0, scratches=int(rng.integers(1, 8)) if on(0.2) else 0,
        condensation=rng.uniform(0.2, 1.0) if on(0.07) else 0.0, fog=rng.uniform(0.05, 0.35) if on(0.1) else 0.0,
        rim_shadow=rng.uniform(0.1, 0.6) if on(0.8) else 0.0, light_angle=light,
        liquid=-rng.uniform(0.7, 0.95) if on(0.08) else 0.0,
    )


def _sample_bezel(rng: np.random.Generator) -> BezelParams:
    style = _choice(rng, ("chrome", "black", "steel", "brass", "painted", "none"), (0.4, 0.25, 0.12, 0.05, 0.11, 0.07))
    color = {"chrome": (215, 215, 210), "black": (70, 70, 72), "steel": (175, 175, 170), "brass": (90, 170, 205),
             "none": (60, 60, 60)}.get(style) or _choice(rng, ((40, 40, 170), (140, 80, 30), (60, 110, 40), (110, 110, 110)))
    width = rng.uniform(0.08, 0.25) if style == "black" else rng.uniform(0.04, 0.2)
    case = tuple(int(c * 0.75) for c in color) if style != "none" else (50, 50, 50)
    return BezelParams(style=style, width=width, color=color, lip=rng.uniform(0.0, 0.04), case_depth=rng.uniform(0.15, 0.7),
                       case_color=case, stem=_choice(rng, ("bottom", "back", "none"), (0.45, 0.4, 0.15)),
                       flange=bool(rng.random() < 0.08))


def _layout_texts(rng: np.random.Generator, scales: list[ScaleParams], ink: Color, free: float,
                  bottom_gap: bool) -> tuple[list[ScaleParams], tuple[TextItem, ...]]:
    """Place unit labels and distractor texts in free slots inside the number rings."""
    slots = [(0.0, rng.uniform(0.22, 0.34)), (0.0, rng.uniform(-0.38, -0.26)), (0.0, rng.uniform(0.4, 0.5)),
             (0.0, rng.uniform(-0.2, -0.14))]
    if bottom_gap:
        slots.append((rng.uniform(-0.05, 0.05), rng.uniform(0.68, 0.78)))
    usable = [s for s in slots if abs(s[1]) + 0.05 < free or s[1] > 0.6]
    font = _choice(rng, FONT_KEYS)
    out_scales = []
    for i, s in enumerate(scales):
        if usable and rng.random() < 0.92:
            pos = usable.pop(0 if i == 0 or rng.random() < 0.5 else -1)
            size = min(rng.uniform(0.08, 0.16), max(0.04, (free - abs(pos[1])) * 1.2))
            s = _replace_scale(s, unit_pos=pos, unit_style=TextStyle(font, size, s.color))
        out_scales.append(s)
    texts = []
    candidates = [("brand", brand_name(rng), 0.7, (0.06, 0.13)),
                  ("class", _choice(rng, ("Cl. 1.6", "KL 1.6", "CL.1.0", "1.6", "Kl.2.5", "cl 1")), 0.45, (0.04, 0.08)),
                  ("standard", _choice(rng, ("EN 837-1", "EN 837", "ISO 9001", "ASME B40.100")), 0.3, (0.035, 0.065)),
                  ("serial", f"No {int(rng.integers(10**5, 10**9))}", 0.3, (0.035, 0.06)),
                  ("other", _choice(rng, ("GLYCERINE", "Made in EU", "SAFETY", "OXYGEN", "USE NO OIL", "STAINLESS")), 0.2, (0.035, 0.07))]
    for kind, text, p, (lo, hi) in candidates:
        if not usable or rng.random() > p:
            continue
        pos = usable.pop(int(rng.integers(len(usable))))
        size = rng.uniform(lo, hi)
        limit = 2 * math.sqrt(max(free * free - pos[1] ** 2, 0.0)) if pos[1] < 0.6 else 0.8
        size = min(size, limit / max(1.0, 0.62 * len(text)))
        if size >= 0.025:
            texts.append(TextItem(text, kind, pos, TextStyle(_choice(rng, FONT_KEYS), size, ink)))
    return out_scales, tuple(texts)


def _replace_scale(s: ScaleParams, **kw) -> ScaleParams:
    return replace(s, **kw)


def reverse_direction(params: GaugeParams) -> GaugeParams:
    """The same gauge with every scale running the other way: dial angles are mirrored about the
    axis of symmetry of the primary scale's arc, so the arc stays where it was, its minimum moves to
    the other end, and the stop pin (just past the minimum) and secondary scales follow. The value
    and everything printed off the scales stay; applying it twice gives the gauge back."""
    axis = params.primary.start_angle + params.primary.end_angle  # twice the angle of the arc's middle
    scales = tuple(replace(s, start_angle=axis - s.start_angle, end_angle=axis - s.end_angle) for s in params.scales)
    pin = params.stop_pin
    if pin is not None:
        pin = (axis - pin[0], pin[1], pin[2])
    return replace(params, scales=scales, stop_pin=pin)


def sample_gauge(rng: np.random.Generator, *, clean: bool = False, range_spec: RangeSpec | None = None,
                 unit: str | None = None, value: float | None = None, secondary: bool | None = None,
                 direction: str = "cw") -> GaugeParams:
    """Draw one gauge. ``range_spec``/``unit``/``value``/``secondary`` pin those choices;
    ``direction`` ("cw", "ccw" or "mixed", see the module docstring) which way its scales rise."""
    if direction not in DIRECTIONS:
        raise ValueError(f"direction must be one of {DIRECTIONS}, got {direction!r}")
    ccw = direction == "ccw" or (direction == "mixed" and rng.random() < CCW_SHARE)  # "cw" draws nothing here
    if ccw and range_spec is None and rng.random() < CCW_SPECIAL:
        range_spec = _choice(rng, CCW_RANGES)
    name, face_color, _, dark = _choice(rng, FACES, [f[2] for f in FACES])
    ink = _choice(rng, INK_DARK if dark else INK_LIGHT)
    face = FaceParams(face_color, 0.0 if clean else rng.uniform(0.0, 0.2), 0.0 if clean else rng.uniform(0.0, 0.04), ink)
    font = _choice(rng, FONT_KEYS)
    primary = sample_primary_scale(rng, ink, font, range_spec, unit)
    primary = _replace_scale(primary, bands=_bands(rng, primary))
    scales = [primary]
    want_secondary = rng.random() < 0.25 if secondary is None else secondary
    if want_secondary:
        sec = sample_secondary_scale(rng, primary, font, dark)
        if sec is not None:
            scales.append(sec)
    free = number_ring_inner(scales[-1]) - 0.02
    centred = abs(((primary.start_angle + primary.end_angle) / 2 + math.pi / 2 + math.pi) % (2 * math.pi) - math.pi) < 0.1
    scales, texts = _layout_texts(rng, scales, ink, free, centred and primary.sweep <= math.radians(285))
    needle = _sample_needle(rng, primary, dark, clean)
    stop_gap = rng.uniform(0.03, 0.1)
    at_stop = False
    if value is None:
        u = rng.random()
        if u < 0.08:
            value, at_stop = primary.value_at(primary.start_angle - stop_gap), True  # still clockwise: mirrored below
        elif u < 0.13:
            value = primary.min
        elif u < 0.16:
            value = primary.max
        else:
            value = rng.uniform(primary.min, primary.max)
    stop_pin = None
    if rng.random() < 0.7:
        r_pin = needle.tip_radius * rng.uniform(0.55, 0.85)
        pin = rng.uniform(0.015, 0.03)
        half = needle.width / 2 + (needle.tip_width - needle.width) / 2 * r_pin / needle.tip_radius
        if needle.shape == "lance":
            half = max(half, needle.width * 0.9)
        stop_pin = (primary.start_angle - stop_gap - (half + pin) / r_pin, r_pin, pin)
    screws = ()
    if rng.random() < 0.35:
        sx, sy = rng.uniform(0.1, 0.2), rng.uniform(0.25, 0.45)
        # keep clear of texts printed at the same height (unit labels usually sit between the screws)
        labels = [(s.unit_pos, s.unit_style.size, s.unit_text) for s in scales if s.unit_pos is not None]
        labels += [(t.center, t.style.size, t.text) for t in texts]
        for (x, y), size, text in labels:
            if abs(y - sy) < size * 0.6 + 0.04:
                sx = max(sx, abs(x) + 0.31 * size * len(text) + 0.05)
        if math.hypot(sx, sy) < free:
            screws = ((-sx, sy), (sx, sy))
    params = GaugeParams(face=face, bezel=_sample_bezel(rng), scales=tuple(scales), needle=needle,
                         glass=_sample_glass(rng, clean), value=float(value), at_stop=at_stop, stop_pin=stop_pin,
                         screws=screws, screw_radius=rng.uniform(0.02, 0.035), texts=texts,
                         texture_seed=int(rng.integers(2**31)), stop_gap=stop_gap)
    return reverse_direction(params) if ccw else params
