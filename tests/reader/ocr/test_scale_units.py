"""Which printed unit names which scale: the conversion between two fitted scales' slopes first,
then where the units are printed; no unit rather than a guess."""

from __future__ import annotations

import math

import pytest

from gauged.reader.ocr.scale_units import conversion_pair, label_scales
from gauged.reader.ocr.units import PrintedUnit
from gauged.types import Ellipse, ScaleModel

RING = Ellipse(128.0, 128.0, 100.0, 100.0, 0.0)
SPAN = math.radians(270.0)


def _scale(low: float, high: float) -> ScaleModel:
    """A scale from ``low`` to ``high`` over 270 degrees of dial angle."""
    slope = (high - low) / SPAN
    return ScaleModel(RING, slope, low, 0.0, low, high)


def _units(scales, *printed: tuple[str, float]) -> list[str | None]:
    return [s.unit for s in label_scales(scales, [PrintedUnit(u, 1.0, r) for u, r in printed])]


def test_two_scales_take_the_units_their_slopes_convert_between():
    # 0..6 bar outside, 0..87 psi inside: psi printed farther out does not decide it, the factor 14.5 does
    assert _units([_scale(0, 6), _scale(0, 87)], ("psi", 0.9), ("bar", 0.5)) == ["bar", "psi"]
    assert _units([_scale(0, 160), _scale(0, 11)], ("bar", 0.9), ("psi", 0.5)) == ["psi", "bar"]
    assert _units([_scale(0, 160), _scale(0, 1100)], ("kPa", 0.4), ("psi", 0.6)) == ["psi", "kPa"]
    # temperature scales convert by 1.8 per degree (their offset does not change the slopes)
    assert _units([_scale(-40, 150), _scale(-40, 65.6)], ("degF", 0.8), ("degC", 0.7)) == ["degF", "degC"]


def test_one_printed_unit_names_its_partner_only_when_one_unit_fits():
    # bar inside at 14.75x: psi is the only unit that far from bar
    assert _units([_scale(0, 5900), _scale(0, 400)], ("bar", 0.85)) == ["psi", "bar"]
    # psi outside at 14.3x: bar (14.5) and kg/cm2 (14.2) both fit, so the inner scale gets no unit
    assert _units([_scale(0, 60), _scale(0, 4.2)], ("psi", 1.0)) == ["psi", None]
    # no conversion fits: the printed unit is the outer (main) scale's, the inner one gets none
    assert _units([_scale(0, 2500), _scale(0, 400)], ("kPa", 0.5)) == ["kPa", None]


def test_a_lone_scale_takes_the_unit_printed_farthest_from_the_centre():
    assert _units([_scale(0, 5000)], ("bar", 0.51), ("psi", 0.77)) == ["psi"]
    assert _units([_scale(0, 16)], ("psi", 0.36), ("bar", 0.97)) == ["bar"]
    assert _units([_scale(0, 16)], ("bar", 0.3)) == ["bar"]
    assert _units([_scale(0, 16)]) == [None]
    # positions unknown: nothing decides between two units
    assert [s.unit for s in label_scales([_scale(0, 16)], [PrintedUnit("bar", 1.0), PrintedUnit("psi", 1.0)])] == [None]


@pytest.mark.parametrize("outer,inner", [(1.0, 0.0), (1.0, -1.0), (0.0, 1.0)])
def test_scales_that_do_not_both_rise_have_no_conversion(outer, inner):
    assert conversion_pair(outer, inner, ["bar", "psi"]) is None
