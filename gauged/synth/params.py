"""Parameter records of one gauge: everything the renderer needs to draw it, and nothing random.

Lengths are in *face units* (face radius = 1, pivot at the origin, ``x`` right, ``y`` down), angles
are dial-frame image angles in radians (``atan2(dy, dx)`` with ``y`` down, so positive turns
clockwise), colours are BGR tuples of 0-255 ints. A scale's ``start_angle`` is always the angle of its
minimum and ``end_angle`` that of its maximum, so a scale whose values rise counter-clockwise (a US
vacuum gauge, 0 on the right and 30 inHg on the left) has ``end_angle < start_angle``.
:mod:`gauged.synth.sampling` draws these records
from a ``numpy.random.Generator``; rendering a record is deterministic.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

Color = tuple[int, int, int]


@dataclass(frozen=True, slots=True)
class TextStyle:
    font: str  # key of gauged.synth.fonts.FONTS
    size: float  # em size in face units
    color: Color


@dataclass(frozen=True, slots=True)
class Band:
    """A coloured zone of a scale between two values, as a ring sector ``inner..outer``."""

    start: float
    end: float
    color: Color
    inner: float
    outer: float


@dataclass(frozen=True, slots=True)
class ScaleParams:
    """One scale (primary outer scale or a secondary, usually inner, unit conversion)."""

    role: str  # "primary" | "secondary"
    min: float
    max: float
    unit: str  # normalised: bar, mbar, kPa, MPa, psi, kg/cm2, inHg, degC, degF, %
    unit_text: str  # as printed, e.g. "kg/cm²"
    start_angle: float  # dial angle of ``min``
    end_angle: float  # dial angle of ``max``: > start_angle when values rise clockwise, < when counter-clockwise
    radius: float  # major notch centres lie on this circle
    label_step: float
    major_step: float
    minor_step: float
    tick_side: str  # "in" | "out" | "centre": which way ticks grow from the baseline
    major_style: str  # "line" | "wedge" | "dot"
    minor_style: str  # "line" | "dot" | "none"
    major_length: float
    minor_length: float
    major_width: float
    minor_width: float
    baseline: bool
    baseline_width: float
    color: Color
    numbers: TextStyle
    number_side: str  # "in" | "out" (relative to the notches)
    number_gap: float
    number_orientation: str  # "upright" | "tangent"
    decimals: int
    decimal_comma: bool = False
    unit_pos: tuple[float, float] | None = None
    unit_style: TextStyle | None = None
    bands: tuple[Band, ...] = ()

    def angle_of(self, value: float) -> float:
        """Dial angle of ``value`` (linear scale; extrapolates outside [min, max])."""
        return self.start_angle + (value - self.min) / (self.max - self.min) * (self.end_angle - self.start_angle)

    def value_at(self, angle: float) -> float:
        return self.min + (angle - self.start_angle) / (self.end_angle - self.start_angle) * (self.max - self.min)

    @property
    def direction(self) -> str:
        """``"cw"`` when values rise clockwise on the dial, ``"ccw"`` when they rise counter-clockwise."""
        return "cw" if self.end_angle > self.start_angle else "ccw"

    @property
    def sweep(self) -> float:
        """Angle between the ends of the scale, radians, positive in both directions."""
        return abs(self.end_angle - self.start_angle)

    @property
    def arc(self) -> tuple[float, float]:
        """The arc's ends in clockwise order: (clockwise-first, clockwise-last) dial angles."""
        return (self.start_angle, self.end_angle) if self.direction == "cw" else (self.end_angle, self.start_angle)

    def below_min(self, gap: float) -> float:
        """Dial angle ``gap`` radians past the minimum's end, away from the scale (where a stop pin sits)."""
        return self.start_angle - gap if self.direction == "cw" else self.start_angle + gap


@dataclass(frozen=True, slots=True)
class FaceParams:
    color: Color
    gradient: float  # darkening towards the rim, 0..0.3
    texture: float  # paper/paint grain amplitude, 0..0.06
    ink: Color  # default print colour


@dataclass(frozen=True, slots=True)
class BezelParams:
    style: str  # "chrome" | "black" | "brass" | "painted" | "steel" | "none"
    width: float  # ring width in face units
    color: Color
    lip: float  # dark inner lip width
    case_depth: float  # depth of the case behind the face (drawn when tilted)
    case_color: Color
    stem: str  # "bottom" | "back" | "none"
    stem_color: Color = (150, 170, 185)
    flange: bool = False


@dataclass(frozen=True, slots=True)
class NeedleParams:
    shape: str  # "line" | "tapered" | "arrow" | "lance"
    color: Color
    width: float  # at the pivot
    tip_radius: float  # distance pivot -> tip
    tip_width: float
    counterweight: str  # "none" | "disc" | "tail" | "ring" | "paddle"
    tail_length: float
    tail_width: float
    hub_radius: float
    hub_color: Color
    hub_style: str  # "plain" | "chrome" | "screw"
    shadow_offset: tuple[float, float]
    shadow_strength: float
    shadow_blur: float  # face units


@dataclass(frozen=True, slots=True)
class GlassParams:
    glare: float  # specular highlight strength 0..0.8
    glare_center: tuple[float, float]
    glare_size: tuple[float, float]  # semi-axes, face units
    glare_angle: float
    reflections: int  # window-like soft reflections
    dirt: float  # low-frequency darkening 0..0.35
    specks: int
    scratches: int
    condensation: float  # 0..1 droplets density
    fog: float  # 0..0.5 loss of contrast
    rim_shadow: float  # shadow of the bezel on the face 0..0.6
    light_angle: float  # direction the light comes from (dial frame)
    liquid: float = 0.0  # glycerine-filled: y (face units, < 0) of the liquid surface; 0 = dry gauge


@dataclass(frozen=True, slots=True)
class TextItem:
    """A printed text that is not a scale number: brand, serial, class, standard, unit-like words."""

    text: str
    kind: str  # "brand" | "serial" | "class" | "standard" | "other"
    center: tuple[float, float]
    style: TextStyle
    rotation: float = 0.0


@dataclass(frozen=True, slots=True)
class GaugeParams:
    """One complete gauge. ``value`` is the reading on ``scales[0]`` (the primary scale); with
    ``at_stop`` the needle rests on the stop pin at ``value`` (below the scale minimum)."""

    face: FaceParams
    bezel: BezelParams
    scales: tuple[ScaleParams, ...]
    needle: NeedleParams
    glass: GlassParams
    value: float
    at_stop: bool = False
    stop_pin: tuple[float, float, float] | None = None  # (dial angle, radius, pin radius)
    screws: tuple[tuple[float, float], ...] = ()  # centres of the face's fixing screws
    screw_radius: float = 0.03
    texts: tuple[TextItem, ...] = ()
    texture_seed: int = 0  # seeds the deterministic textures (dirt, grain, droplets)
    stop_gap: float = 0.07  # radians between the stop pin rest angle and the scale start

    @property
    def primary(self) -> ScaleParams:
        return self.scales[0]

    @property
    def needle_angle(self) -> float:
        """Dial angle of the needle."""
        return self.primary.angle_of(self.value)

    @property
    def rest_value(self) -> float:
        """Value the needle shows resting on the stop pin, ``stop_gap`` below the primary scale's minimum."""
        return self.primary.value_at(self.primary.below_min(self.stop_gap))

    def with_value(self, value: float, at_stop: bool = False) -> GaugeParams:
        """The same gauge with the needle at another value (used by sequences)."""
        return replace(self, value=value, at_stop=at_stop)
