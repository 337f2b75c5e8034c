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

from gauged.reader.ocr_engine import TextBox
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
    s = re.sub(r"^(?:x?\d+x|x\d+)", "", s)  # "100xkpa", "x100" multipliers
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


def read_unit(boxes: Sequence[TextBox], circle: tuple[float, float, float] | None = None) -> UnitMatch | None:
    """The dial's unit from all its texts: the best match by score x OCR score, nearer the dial
    centre first on ties (units are printed on the face, inside the scale). None when no text
    names a unit."""
    found = []
    for b in boxes:
        m = match_unit(b.text)
        if not m:
            continue
        d = 0.0 if circle is None else math.dist(b.center, circle[:2]) / circle[2]
        found.append((m.score * b.score, -d, m))
    if not found:
        return None
    return max(found, key=lambda t: (t[0], t[1]))[2]
