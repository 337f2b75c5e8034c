"""Catalogue of real gauge scales: ranges, divisions, units, unit conversions, number formatting.

Ranges and divisions follow what EN 837-1 pressure gauges and common thermometers print: a range
like 0-16 bar is numbered every 2 bar with a major notch every 1 or 2 bar and minor divisions of
0.2 or 0.5 bar. Secondary (inner) scales are unit conversions of the primary one (bar and psi on
the same dial), numbered at their own round values.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True, slots=True)
class Division:
    """Numbers every ``label`` units, major notches every ``major``, minor every ``minor``."""

    label: float
    major: float
    minor: float


@dataclass(frozen=True, slots=True)
class RangeSpec:
    min: float
    max: float
    divisions: tuple[Division, ...]
    units: tuple[str, ...]


def _d(*triples: tuple[float, float, float]) -> tuple[Division, ...]:
    return tuple(Division(*t) for t in triples)


RANGES: tuple[RangeSpec, ...] = (
    RangeSpec(0, 1, _d((0.1, 0.1, 0.02), (0.2, 0.1, 0.02), (0.2, 0.2, 0.05)), ("bar", "MPa", "kg/cm2")),
    RangeSpec(0, 1.6, _d((0.2, 0.2, 0.05), (0.4, 0.2, 0.05), (0.2, 0.1, 0.02)), ("bar", "MPa", "kg/cm2")),
    RangeSpec(0, 2.5, _d((0.5, 0.5, 0.05), (0.5, 0.5, 0.1), (0.5, 0.25, 0.05)), ("bar", "MPa", "kg/cm2")),
    RangeSpec(0, 4, _d((1, 0.5, 0.1), (0.5, 0.5, 0.1), (1, 1, 0.1)), ("bar", "kg/cm2", "MPa")),
    RangeSpec(0, 6, _d((1, 1, 0.1), (1, 0.5, 0.2), (1, 1, 0.2)), ("bar", "kg/cm2")),
    RangeSpec(0, 10, _d((1, 1, 0.2), (2, 1, 0.2), (1, 1, 0.1), (2, 2, 0.5)), ("bar", "kg/cm2")),
    RangeSpec(0, 16, _d((2, 1, 0.5), (2, 2, 0.2), (4, 2, 0.5), (2, 1, 0.2)), ("bar", "kg/cm2")),
    RangeSpec(0, 25, _d((5, 5, 0.5), (5, 1, 0.5), (5, 5, 1)), ("bar", "kg/cm2", "psi")),
    RangeSpec(0, 40, _d((5, 5, 1), (10, 5, 1), (10, 10, 1)), ("bar", "psi", "degC")),
    RangeSpec(0, 60, _d((10, 10, 1), (10, 5, 1), (10, 10, 2)), ("bar", "psi", "kPa", "mbar", "degC")),
    RangeSpec(0, 100, _d((10, 10, 2), (20, 10, 2), (10, 10, 1), (20, 20, 5)), ("psi", "kPa", "mbar", "degC", "%")),
    RangeSpec(0, 160, _d((20, 20, 5), (20, 10, 2), (40, 20, 5)), ("psi", "kPa", "mbar", "degC", "bar")),
    RangeSpec(0, 250, _d((50, 50, 5), (50, 25, 5), (50, 10, 5), (50, 50, 10)), ("kPa", "mbar", "psi", "bar")),
    RangeSpec(0, 400, _d((50, 50, 10), (100, 50, 10), (50, 50, 5)), ("kPa", "mbar", "psi", "bar")),
    RangeSpec(-1, 0, _d((0.2, 0.1, 0.02), (0.1, 0.1, 0.02), (0.2, 0.2, 0.05)), ("bar",)),
    RangeSpec(-1, 3, _d((1, 0.5, 0.1), (1, 1, 0.1), (0.5, 0.5, 0.1)), ("bar",)),
    RangeSpec(-30, 50, _d((10, 10, 2), (10, 10, 1), (20, 10, 2)), ("degC",)),
    RangeSpec(0, 0.25, _d((0.05, 0.05, 0.005), (0.05, 0.05, 0.01)), ("MPa", "bar")),
    # A few more that plants use, for variety.
    RangeSpec(0, 300, _d((50, 50, 5), (50, 10, 5), (100, 50, 10)), ("psi", "kPa", "degF")),
    RangeSpec(0, 200, _d((20, 20, 5), (50, 10, 2), (20, 10, 2)), ("psi", "kPa", "degC")),
    RangeSpec(0, 120, _d((20, 10, 2), (10, 10, 2)), ("degC",)),
    RangeSpec(-30, 0, _d((5, 5, 1), (10, 5, 1)), ("inHg",)),
)

# Scales whose values rise counter-clockwise: vacuum, compound and low-range decimal scales as real
# ones print them. Only counter-clockwise sampling draws from this list (``sample_gauge(direction=
# "ccw" | "mixed")``), so the clockwise default draws what it always drew for a seed.
CCW_RANGES: tuple[RangeSpec, ...] = (
    RangeSpec(-1, 0, _d((0.2, 0.1, 0.02), (0.1, 0.1, 0.02), (0.2, 0.2, 0.05)), ("bar",)),
    RangeSpec(-100, 0, _d((20, 10, 2), (10, 10, 2), (20, 20, 5)), ("kPa",)),
    RangeSpec(0, 30, _d((5, 5, 1), (10, 5, 1), (5, 1, 0.5)), ("inHg",)),  # US vacuum: 0 on the right, 30 on the left
    RangeSpec(-1, 3, _d((1, 0.5, 0.1), (1, 1, 0.1), (0.5, 0.5, 0.1)), ("bar",)),
    RangeSpec(-1, 1.5, _d((0.5, 0.5, 0.1), (0.5, 0.25, 0.05)), ("bar",)),
    RangeSpec(-30, 50, _d((10, 10, 2), (10, 10, 1), (20, 10, 2)), ("degC",)),
    RangeSpec(-40, 40, _d((10, 10, 2), (20, 10, 2)), ("degC", "degF")),
    RangeSpec(0, 1.6, _d((0.2, 0.2, 0.05), (0.4, 0.2, 0.05), (0.2, 0.1, 0.02)), ("bar", "MPa")),
    RangeSpec(0, 2.5, _d((0.5, 0.5, 0.05), (0.5, 0.5, 0.1), (0.5, 0.25, 0.05)), ("MPa", "bar")),
    RangeSpec(0, 0.6, _d((0.1, 0.1, 0.02), (0.2, 0.1, 0.02)), ("MPa", "bar")),
    RangeSpec(-0.1, 0, _d((0.02, 0.01, 0.002), (0.02, 0.02, 0.005), (0.01, 0.01, 0.002)), ("MPa",)),
    RangeSpec(-0.1, 0.15, _d((0.05, 0.05, 0.01), (0.05, 0.025, 0.005)), ("MPa",)),
)

# How each unit is printed (first variant most common).
UNIT_TEXT: dict[str, tuple[str, ...]] = {
    "bar": ("bar", "BAR", "bar", "Bar"),
    "mbar": ("mbar", "mbar", "MBAR"),
    "kPa": ("kPa", "kPa", "KPa", "KPA"),
    "MPa": ("MPa", "MPa", "MPA"),
    "psi": ("psi", "PSI", "psi", "lb/in²"),
    "kg/cm2": ("kg/cm²", "kgf/cm²", "kg/cm2", "KG/CM²"),
    "inHg": ("inHg", "in Hg", "INHG"),
    "degC": ("°C", "°C", "°C", "C"),
    "degF": ("°F", "°F", "F"),
    "%": ("%", "%RH", "%"),
}

# Secondary scales: (primary unit, secondary unit, factor, offset): s = factor * p + offset.
CONVERSIONS: tuple[tuple[str, str, float, float], ...] = (
    ("bar", "psi", 14.5038, 0.0),
    ("bar", "kPa", 100.0, 0.0),
    ("bar", "inHg", 29.53, 0.0),
    ("MPa", "psi", 145.038, 0.0),
    ("MPa", "bar", 10.0, 0.0),
    ("kg/cm2", "psi", 14.2233, 0.0),
    ("kg/cm2", "kPa", 98.0665, 0.0),
    ("psi", "bar", 1.0 / 14.5038, 0.0),
    ("psi", "kPa", 6.89476, 0.0),
    ("kPa", "psi", 0.145038, 0.0),
    ("degC", "degF", 1.8, 32.0),
    ("degF", "degC", 1.0 / 1.8, -32.0 / 1.8),
    ("inHg", "bar", 1.0 / 29.53, 0.0),
)

_NICE = (1.0, 2.0, 2.5, 5.0)


def nice_division(span: float, labels: int = 6) -> Division:
    """A round division of ``span`` giving about ``labels`` numbers (for converted scales)."""
    raw = span / max(1, labels)
    exp = math.floor(math.log10(raw))
    label = min((n * 10.0**exp for n in _NICE + (10.0,)), key=lambda s: abs(math.log(s / raw)))
    major = label / 2.0 if label / 2.0 >= raw / 2.5 and _is_round(label / 2.0) else label
    minor = label / 10.0 if _is_round(label / 10.0) else label / 5.0
    return Division(label, major, minor)


def _is_round(x: float) -> bool:
    mant = x / 10.0 ** math.floor(math.log10(x))
    return any(abs(mant - n) < 1e-9 for n in _NICE)


def grid(lo: float, hi: float, step: float) -> np.ndarray:
    """Multiples of ``step`` in ``[lo, hi]`` (inclusive, tolerant of float error)."""
    k0 = math.ceil(lo / step - 1e-9)
    k1 = math.floor(hi / step + 1e-9)
    return np.round(np.arange(k0, k1 + 1) * step, 10)


def decimals_of(step: float) -> int:
    """How many decimals a number printed every ``step`` needs (0.25 -> 2, 0.5 -> 1, 5 -> 0)."""
    for d in range(6):
        if abs(step * 10**d - round(step * 10**d)) < 1e-9:
            return d
    return 6


def format_number(value: float, decimals: int, comma: bool = False) -> str:
    """Scale number as printed: ``-0.5``, ``2.5`` (or ``2,5`` with ``comma``), ``10``; never ``-0``."""
    text = f"{value:.{decimals}f}"
    if float(text) == 0.0:
        text = text.lstrip("-")
    return text.replace(".", ",") if comma else text


def convert(unit_from: str, unit_to: str) -> tuple[float, float]:
    """(factor, offset) of a known conversion; raises KeyError for an unknown pair."""
    for a, b, f, o in CONVERSIONS:
        if a == unit_from and b == unit_to:
            return f, o
    raise KeyError(f"no conversion {unit_from} -> {unit_to}")


def conversions_from(unit: str) -> list[str]:
    return [b for a, b, _, _ in CONVERSIONS if a == unit]
