"""The unit printed on a dial, read against a vocabulary with OCR-tolerant matching.

A unit string is normalised (case folded, ``²``/``º``/``℃``/``℉`` spelled out, a trailing gauge
suffix such as ``(g)`` dropped) and compared with every spelling in :data:`UNIT_SPELLINGS`; a match
within a small edit distance after mapping OCR look-alikes (``0``/``o``, ``1``/``l``, ``5``/``s``,
``rn``/``m``)
gives the canonical unit. Single letters (``C``, ``F``, ``A``, ``V``) are units only when they are
the whole text. Dial words that are not units (brands, standards, "OIL") are :data:`DISTRACTORS`.

Example:
    >>> match_unit("KPA").unit, match_unit("kg/cm²(g)").unit, match_unit("°C").unit
    ('kPa', 'kg/cm2', 'degC')
    >>> match_unit("WIKA").reason
    'distractor'
"""

from __future__ import annotations

import math
import re
from collections.abc import Sequence
from dataclasses import dataclass

from gauged.reader.ocr.text import TextBox
from gauged.types import StageFailure

# canonical unit -> spellings seen on dials (lower case after normalise())
UNIT_SPELLINGS: dict[str, tuple[str, ...]] = {
    "bar": ("bar", "bars"),
    "mbar": ("mbar", "millibar"),
    "kPa": ("kpa",),
    "MPa": ("mpa",),
    "Pa": ("pa",),
    "psi": ("psi", "p.s.i.", "lb/in2", "lbf/in2", "psig"),
    "kg/cm2": ("kg/cm2", "kgf/cm2", "kg/cm", "kgf/cm", "kgcm2", "kg/sqcm"),
    "inHg": ("inhg", "in.hg", "\"hg", "inchhg"),
    "mmHg": ("mmhg", "torr"),
    "inH2O": ("inh2o", "in.h2o", "inwc", "\"h2o", "inwg"),
    "mmH2O": ("mmh2o", "mmwc", "mmwg"),
    "degC": ("degc", "°c", "oc", "c"),
    "degF": ("degf", "°f", "of", "f"),
    "%": ("%", "%rh"),
    "A": ("a",),
    "V": ("v",),
    "mA": ("ma",),
    "kV": ("kv",),
    "rpm": ("rpm", "r/min", "x100rpm", "x1000rpm"),
    "km/h": ("km/h", "kmh"),
    "knots": ("knots", "kn"),
}
# single letters and short codes: exact matches only (a fragment of a word must not become a unit)
_EXACT_ONLY = {"a", "v", "c", "f", "oc", "of", "pa", "ma", "kv", "kn", "%"}
DISTRACTORS = frozenset({
    "en", "din", "iso", "asme", "ansi", "cl", "kl", "class", "klasse", "made", "in", "germany", "china", "usa",
    "stainless", "steel", "316l", "316", "ss", "glycerin", "glycerine", "liquid", "filled", "oil", "water",
    "air", "gas", "fuel", "vacuum", "pressure", "gauge", "gage", "manometer", "thermometer", "wika", "ashcroft",
    "trerice", "winters", "noshok", "baumer", "budenberg", "wise", "general", "holley", "acurite", "no", "sn",
    "serial", "max", "min", "temp", "boost", "trans", "oxygen", "acetylene", "use", "no oil", "safety",
})
# canonical unit -> (quantity, size of one unit in the quantity's base unit): scales of one quantity
# convert by the ratio of their sizes (temperature scales also by an offset, which slopes do not see)
UNIT_SIZE: dict[str, tuple[str, float]] = {
    "Pa": ("pressure", 1.0), "kPa": ("pressure", 1e3), "MPa": ("pressure", 1e6), "mbar": ("pressure", 100.0),
    "bar": ("pressure", 1e5), "psi": ("pressure", 6894.757), "kg/cm2": ("pressure", 98066.5),
    "inHg": ("pressure", 3386.389), "mmHg": ("pressure", 133.3224), "inH2O": ("pressure", 249.0889),
    "mmH2O": ("pressure", 9.80665),
    "degC": ("temperature", 1.0), "degF": ("temperature", 5.0 / 9.0),
    "km/h": ("speed", 1.0), "knots": ("speed", 1.852),
}
WORD_MIN_SCORE = 0.9  # a word of a longer text must spell its unit (look-alike digits allowed), not come near
# one: the fuzzy match took a brand's "Barsa" for "bars" (a degC dial of a synthetic held-out set read "bar")
_SUFFIX = re.compile(r"\((?:g|a|gauge|abs)\)$")
_LOOKALIKE = str.maketrans({"0": "o", "1": "l", "5": "s", "|": "l"})


@dataclass(frozen=True, slots=True)
class UnitMatch:
    """A unit read from ``text``: canonical ``unit`` and a match ``score`` in (0, 1]."""

    unit: str
    text: str
    score: float


def normalise(text: str) -> str:
    """Lower-case unit text with symbols spelled the vocabulary's way ("kgf/cm²" -> "kgf/cm2")."""
    s = text.strip().replace(" ", "").replace("×", "x").replace("²", "2").replace("º", "°").replace("˚", "°")
    s = _SUFFIX.sub("", s.replace("℃", "°c").replace("℉", "°f").lower())
    return s.strip("()[].,:;'")


def _fail(reason: str, detail: str) -> StageFailure:
    # a verdict on one string, kept inside the OCR stage: not a failure-metric label
    return StageFailure(stage="ocr", reason=reason, detail=detail)


def _edit_distance(a: str, b: str) -> int:
    prev = list(range(len(b) + 1))
    for i, ca in enumerate(a, 1):
        cur = [i]
        for j, cb in enumerate(b, 1):
            cur.append(min(prev[j] + 1, cur[j - 1] + 1, prev[j - 1] + (ca != cb)))
        prev = cur
    return prev[-1]


def match_unit(text: str) -> UnitMatch | StageFailure:
    """The canonical unit named by ``text`` or a failure (stage ``ocr``) with reason ``empty``,
    ``distractor`` (a known non-unit dial word) or ``no_unit``.

    Exact spellings score 1.0 (a lone letter such as "C" 0.6); a spelling of four or more characters matches at edit distance 1
    (after mapping digit look-alikes to letters) with score 0.7. "x 100 kPa"-style multipliers keep
    the unit ("100xkPa" -> kPa).
    """
    s = normalise(text)
    if not s:
        return _fail("empty", "no unit text")
    s = re.sub(r"^(?:[x*]?\d+[x*]|[x*]\d+)", "", s)  # "100xkpa", "x100", "*100k pa" multipliers
    if s in DISTRACTORS or text.strip().lower() in DISTRACTORS:
        return _fail("distractor", f"{text!r} is a dial word, not a unit")
    for unit, spellings in UNIT_SPELLINGS.items():
        if s in spellings:
            return UnitMatch(unit, text, 0.6 if len(s) == 1 and s != "%" else 1.0)
    fuzzy = s.translate(_LOOKALIKE).replace("rn", "m")
    best: tuple[int, str] | None = None
    for unit, spellings in UNIT_SPELLINGS.items():
        for sp in spellings:
            if sp in _EXACT_ONLY or len(sp) < 3:
                continue
            if fuzzy == sp:
                return UnitMatch(unit, text, 0.9)
            if len(sp) >= 4 and abs(len(sp) - len(fuzzy)) <= 1:
                d = _edit_distance(fuzzy, sp)
                if d <= 1 and (best is None or d < best[0]):
                    best = (d, unit)
    if best is not None:
        return UnitMatch(best[1], text, 0.7)
    return _fail("no_unit", f"{text!r} names no known unit")


@dataclass(frozen=True, slots=True)
class PrintedUnit:
    """A unit read on a dial: canonical ``unit``, ``score`` (match x OCR score) and ``radius``, the
    distance of its text from the dial centre in scale radii (None when the circle is unknown)."""

    unit: str
    score: float
    radius: float | None = None


def printed_units(boxes: Sequence[TextBox], circle: tuple[float, float, float] | None = None
                  ) -> tuple[PrintedUnit, ...]:
    """Every distinct unit the dial's texts name, each by its best text, best first: by score x OCR
    score, nearer the dial centre first on ties (units are printed on the face, inside the scale).
    Empty when no text names a unit. Which one names which scale: :mod:`gauged.reader.ocr.scale_units`.

    A text of several words that names no unit whole is read word by word (words of two or more
    characters, spelled right): a dual-scale dial prints "Knots km/h" on one line, a gauge "OIL PSI".
    """
    best: dict[str, tuple[float, float, PrintedUnit]] = {}
    for b in boxes:
        radius = None if circle is None else math.dist(b.center, circle[:2]) / circle[2]
        for m in _units_named(b.text):
            key = (m.score * b.score, -(radius or 0.0))
            if m.unit not in best or key > best[m.unit][:2]:
                best[m.unit] = (*key, PrintedUnit(m.unit, m.score * b.score, radius))
    return tuple(entry[2] for entry in sorted(best.values(), key=lambda e: e[:2], reverse=True))


def names_unit(text: str, min_score: float = 0.0) -> bool:
    """Whether ``text`` names a unit, whole or by one of its words (:func:`printed_units`), with a
    match score of at least ``min_score`` (:func:`match_unit`: 1.0 spelled, 0.6 a lone letter)."""
    return any(m.score >= min_score for m in _units_named(text))


def _units_named(text: str) -> list[UnitMatch]:
    """The units ``text`` names: itself whole, else each of its words of two or more characters that
    spells one (:data:`WORD_MIN_SCORE`)."""
    whole = match_unit(text)
    if whole:
        return [whole]
    words = [w for w in text.split() if len(w) >= 2]
    if len(words) < 2:
        return []
    return [m for w in words if (m := match_unit(w)) and m.score >= WORD_MIN_SCORE]
