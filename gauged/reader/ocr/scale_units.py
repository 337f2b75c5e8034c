"""Which of the units printed on a dial names which of its scales.

A dual-scale dial prints two units (bar and psi, kPa and psi, degC and degF), and the OCR cannot
tell from the text alone which belongs to the scale it read. Giving every scale the best-read unit
labelled a real 0..5000 psi scale "bar" and a 0..16 bar scale "psi": a reading in the wrong unit is
off by the conversion factor, 14.5x for bar and psi. The evidence, strongest first:

1. **The conversion between two fitted scales.** Both scales measure one pressure at one needle
   angle, so their slopes (value per radian) differ by the conversion factor of their units:
   ``slope_outer / slope_inner = size(inner) / size(outer)``. A 0..6 scale beside a 0..87 one is bar
   outside and psi inside, not the other way round. The pair of units whose factor matches within
   :data:`RATIO_TOLERANCE` names both scales; a unit that was not printed (or not read) is named only
   when it is the one unit that fits the factor with a printed one (bar's partner at 14.5 is psi, but
   psi's at 14.3 is bar or kg/cm2, so then the scale gets no unit).
2. **Where the units are printed.** With several units and one scale read (the reader takes a lone
   ring for the main, outer scale), the unit printed farthest from the dial centre is the outer
   scale's: on every one of 13 real dual-unit dials of the needle-polygons photos that the reader
   read, the main scale's unit stands below or outside the other's. Measured in docs/accuracy.md.
   The synthetic engine does not follow this convention (it places the units at random
   slots), so the rule is not learnt from it.

With one unit printed and one scale, the scale gets that unit, as before. When nothing decides, a
scale gets no unit rather than a guess.
"""

from __future__ import annotations

import itertools
from collections.abc import Sequence
from dataclasses import replace

from gauged.reader.ocr.units import UNIT_SIZE, PrintedUnit
from gauged.types import ScaleModel

RATIO_TOLERANCE = 0.06  # relative: how near the slopes' ratio must come to a conversion factor


def label_scales(scales: Sequence[ScaleModel], printed: Sequence[PrintedUnit]) -> list[ScaleModel]:
    """``scales`` (outer first) with the unit each one is printed in, or None where nothing decides.

    ``printed`` are the distinct units read on the dial, best read first
    (:func:`gauged.reader.ocr.units.printed_units`).
    """
    scales = list(scales)
    if not scales:
        return scales
    units = _units_of(scales, printed)
    return [scale if scale.unit == unit else replace(scale, unit=unit) for scale, unit in zip(scales, units, strict=True)]


def _units_of(scales: list[ScaleModel], printed: Sequence[PrintedUnit]) -> list[str | None]:
    names = [p.unit for p in printed]
    if len(scales) >= 2:
        pair = conversion_pair(scales[0].slope, scales[1].slope, names)
        if pair is not None:
            return [pair[0], pair[1]] + [None] * (len(scales) - 2)
    outer = names[0] if len(names) == 1 else _farthest(printed)
    return [outer] + [None] * (len(scales) - 1)


def _farthest(printed: Sequence[PrintedUnit]) -> str | None:
    """The unit printed farthest from the dial centre: the outer scale's, by the dial makers' convention."""
    placed = [p for p in printed if p.radius is not None]
    if not placed:
        return None
    return max(placed, key=lambda p: p.radius).unit


def conversion_pair(outer_slope: float, inner_slope: float, printed: Sequence[str]) -> tuple[str, str] | None:
    """The units (outer, inner) of two scales whose slopes (value per radian) differ by the conversion
    factor of the units, using the ``printed`` ones; None when no pair or more than one fits.

    Pairs with both units printed come first; then pairs with one printed unit, whose partner must be
    the only unit that fits.
    """
    if outer_slope == 0 or inner_slope == 0 or (outer_slope > 0) != (inner_slope > 0):
        return None
    ratio = outer_slope / inner_slope  # = size(inner) / size(outer)
    fits = [(a, b) for a, b in itertools.permutations(UNIT_SIZE, 2)
            if UNIT_SIZE[a][0] == UNIT_SIZE[b][0]
            and abs(ratio / (UNIT_SIZE[b][1] / UNIT_SIZE[a][1]) - 1.0) <= RATIO_TOLERANCE]
    both = [pair for pair in fits if pair[0] in printed and pair[1] in printed]
    if both:
        return both[0] if len(both) == 1 else None
    one = [pair for pair in fits if pair[0] in printed or pair[1] in printed]
    return one[0] if len(one) == 1 else None
