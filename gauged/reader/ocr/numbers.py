"""Scale numbers from OCR strings: parsing, merging split boxes, and the progression filter.

OCR of a dial returns every piece of text on it: the scale numbers, and distractors that also look
numeric (accuracy class "CL 1.6", the standard "EN 837-1", serial numbers, dates, "316L"). This
module turns strings into values while refusing what is not a scale number (:func:`parse_number`),
joins numbers the detector split in two ("0" + ".6", "1" + "6"; :func:`gauged.reader.ocr.fragments.merge_fragments`), and keeps
the markers consistent with a linear scale, whose numbers form an arithmetic progression evenly
spaced in angle, rising clockwise or counter-clockwise (:func:`filter_progression`).

Every rejection is a :class:`~gauged.types.StageFailure` (stage ``ocr``) or a ``(marker, reason)``
pair with a short machine-readable reason. These verdicts on one string or one set of markers stay
inside the OCR stage (:meth:`gauged.reader.stages.ocr.ScaleTextReader.read_markers` reports only
``no_text`` / ``no_numbers``), so they are not labels of the failure metrics.

Example:
    >>> parse_number("O.6").value, parse_number("1,6").value, parse_number("−30").value
    (0.6, 1.6, -30.0)
    >>> parse_number("CL 1.6").reason, parse_number("19070702").reason
    ('accuracy_class', 'serial')
"""

from __future__ import annotations

import functools
import math
import re
from collections.abc import Sequence
from dataclasses import dataclass, replace

import numpy as np

from gauged.types import ScaleMarker, StageFailure

PITCH = 1.2  # text heights: most between the centres of neighbouring characters of one number
MAX_DIGITS = 5  # "10000" is the longest number on a real dial face; longer strings are serials
MINUS_LIKE = "-−–—‐‑~_"
# OCR look-alikes, applied only when the whole string is otherwise numeric.
DIGIT_CONFUSIONS = str.maketrans({"O": "0", "o": "0", "D": "0", "Q": "0", "l": "1", "I": "1", "|": "1",
                                  "i": "1", "!": "1", "S": "5", "s": "5", "B": "8", "Z": "2", "z": "2"})
NICE_MANTISSAS = (1.0, 2.0, 2.5, 5.0)  # the steps printed on real dials, times 10^k

_CLASS = re.compile(r"^(?:CL|KL|CLASS|KLASSE|CLA|ACC)\b\.?\s*\.?\s*\d", re.IGNORECASE)
_CLASS_GLUED = re.compile(r"^(?:CL|KL|K[I1|])\.?\s*\d", re.IGNORECASE)
_STANDARD = re.compile(r"^(?:EN|DIN|ISO|ASME|ANSI|GB|JIS|BS|NS)\b|^(?:EN|DIN|ISO|GB)[\s\-]?\d", re.IGNORECASE)
_DATE = re.compile(r"\d{1,4}[./-]\d{1,2}[./-]\d{2,4}")
_NUMERIC = re.compile(r"^-?(?:\d+(?:\.\d+)?|\.\d+)$")
_SUFFIX_UNITS = ("°C", "°F", "℃", "℉", "°", "%")


@dataclass(frozen=True, slots=True)
class ParsedNumber:
    """A value read from a string. ``text`` is the cleaned numeric text ("-0.5"); ``confusions``
    counts letters read as digits (O->0, l->1, ...); ``sign_doubtful`` says a leading minus may be a
    tick mark beside the number (the progression filter may drop it); ``fragment`` marks a string
    that may be half of a split number (".6", "-")."""

    value: float
    text: str
    decimals: int
    confusions: int = 0
    sign_doubtful: bool = False
    fragment: bool = False


def _fail(reason: str, text: str) -> StageFailure:
    return StageFailure(stage="ocr", reason=reason, detail=f"not a scale number: {text!r}")


def _too_few(detail: str) -> StageFailure:
    return StageFailure(stage="ocr", reason="too_few_numbers", detail=detail)


PARSE_MEMO = 4096  # distinct strings remembered: a dial's passes parse the same few hundred strings again and again


@functools.lru_cache(maxsize=PARSE_MEMO)
def parse_number(text: str) -> ParsedNumber | StageFailure:
    """Parse one OCR string as a scale number, or say why it is not one.

    Pure, and its results are frozen, so each distinct string is parsed once (:data:`PARSE_MEMO`):
    the OCR and scale stages asked it about 360 times per dial, 9 ms of a cold read.

    Accepts decimals with ``.`` or ``,`` (``1,000`` with a non-zero integer part is one thousand),
    minus as ``-``, ``−``, ``–``, ``—``, ``~`` or ``_``, a leading ``+``, trailing tick debris (``16-``,
    ``15.``), a trailing ``°``/``%``/``°C``, and letters misread for digits (O/o/D/Q -> 0, l/I/i/| -> 1,
    S -> 5, B -> 8, Z -> 2) when the rest is numeric; a lone I/l/| is a tick mark, not 1. Rejection reasons: ``empty``, ``text``,
    ``accuracy_class``, ``standard``, ``date``, ``serial`` (more than :data:`MAX_DIGITS` digits),
    ``leading_zero`` ("05"), ``malformed``.
    """
    raw = text.strip()
    if not raw:
        return _fail("empty", text)
    if _CLASS.match(raw) or _CLASS_GLUED.match(raw):
        return _fail("accuracy_class", text)
    if _STANDARD.match(raw):
        return _fail("standard", text)
    if _DATE.search(raw):
        return _fail("date", text)
    s = raw.replace(" ", "")
    for suffix in _SUFFIX_UNITS:
        if s.endswith(suffix) and len(s) > len(suffix):
            s = s[: -len(suffix)]
            break
    sign_doubtful = False
    if s[0] in MINUS_LIKE or s[0] == ":":
        sign_doubtful = s[0] not in "-−"
        s = "-" + s[1:].lstrip(MINUS_LIKE)
    elif s[0] == "+":
        s = s[1:]
    s = s.rstrip(MINUS_LIKE + ".,:'")  # tick marks and dots beside the number
    if s in ("", "-"):
        return ParsedNumber(0.0, "-", 0, fragment=True) if raw[0] in MINUS_LIKE else _fail("malformed", text)
    body = s[1:] if s.startswith("-") else s
    mapped = body.translate(DIGIT_CONFUSIONS)
    if not re.fullmatch(r"[\d.,]+", mapped):
        return _fail("text" if any(c.isalpha() for c in mapped) else "malformed", text)
    confusions = sum(a != b for a, b in zip(body, mapped))
    if confusions and not any(c.isdigit() for c in body) and (len(body) > 1 or body not in "OoZzSB"):
        return _fail("text", text)  # "Il", "SOS", a lone "I" (a tick mark): words, not misread digits
    mapped = _decimal_point(mapped)
    if mapped is None or not _NUMERIC.match(mapped):
        return _fail("malformed", text)
    digits = sum(c.isdigit() for c in mapped)
    if digits > MAX_DIGITS:
        return _fail("serial", text)
    if len(mapped) > 1 and mapped[0] == "0" and mapped[1].isdigit():
        return _fail("leading_zero", text)
    fragment = mapped.startswith(".")
    if fragment:
        mapped = "0" + mapped
    value = float(mapped) * (-1.0 if s.startswith("-") else 1.0)
    decimals = len(mapped.split(".")[1]) if "." in mapped else 0
    out = f"{'-' if value < 0 else ''}{mapped}"
    return ParsedNumber(value, out, decimals, confusions, sign_doubtful and value < 0, fragment)


def _decimal_point(s: str) -> str | None:
    """Resolve ``,`` and ``.`` into one decimal point: ``1,6`` -> ``1.6``, ``1,000`` -> ``1000``."""
    if s.count(",") + s.count(".") > 1:
        return None
    if "," in s:
        head, tail = s.split(",")
        if len(tail) == 3 and head not in ("", "0"):
            return head + tail  # thousands separator
        return f"{head}.{tail}"
    return s


def read_as_digits(text: str) -> bool:
    """Whether OCR read the number as digits, with no letter taken for one ("O" for 0, "S" for 5)."""
    parsed = parse_number(text)
    return bool(parsed) and parsed.confusions == 0


# A dangling point ("0.", "20.") parses as tick debris, but it is a decimal cut short as often: "0." for
# "-0.3", "1" and "2" for "-0.8", "-0.4" made 0..2.2 of a -1..0 vacuum dial (a synthetic render, 195% off).
_DANGLING_POINT = re.compile(r"\d[.,]\s*$")


def printed_decimal(marker: ScaleMarker) -> bool:
    """Whether a number was read with decimals: a fraction, or a whole value printed with them ("1.0")."""
    return marker.value != round(marker.value) or bool(re.search(r"\d[.,]\d", marker.text))


def read_whole(text: str) -> bool:
    """Whether OCR read the number as digits (:func:`read_as_digits`) and whole, with no dangling
    point: the numbers a scale's evidence is made of."""
    return read_as_digits(text) and not _DANGLING_POINT.search(text)


# -- progression filter ---------------------------------------------------------------------------
@dataclass(frozen=True, slots=True)
class ProgressionFit:
    """Markers consistent with one linear scale. ``value = slope * unwrapped_angle + intercept``
    (angles unwrapped from ``gap_angle``), ``step`` the common difference of the kept values,
    ``nice`` whether it is 1, 2, 2.5 or 5 x 10^k, ``rejected`` the other markers with reasons
    (``off_progression``, ``duplicate_value``, ``radius_outlier``, ``no_angle``)."""

    kept: tuple[ScaleMarker, ...]
    rejected: tuple[tuple[ScaleMarker, str], ...]
    slope: float
    intercept: float
    step: float
    nice: bool


def nice_step(step: float, rel: float = 1e-6) -> bool:
    """Is ``step`` of the form m x 10^k with m in {1, 2, 2.5, 5}?"""
    if step <= 0:
        return False
    k = math.floor(math.log10(step))
    m = step / 10.0**k
    return any(abs(m - n) <= rel * n or abs(m - 10 * n) <= rel * n for n in NICE_MANTISSAS)


def _whole_multiples(diffs: np.ndarray, step: float) -> bool:
    """Is every one of ``diffs`` a whole multiple of ``step`` (to a millionth)?"""
    q = diffs / step
    return bool(np.all(np.abs(q - np.round(q)) < 1e-6 * np.maximum(1.0, q)))


def _common_step(values: np.ndarray) -> float:
    """The largest step of which every pairwise difference of ``values`` is a whole multiple."""
    d = np.diff(np.unique(np.round(values, 9)))
    if d.size == 0:
        return 0.0
    for step in sorted({float(x) for x in d}, reverse=True):
        if step > 0 and _whole_multiples(d, step):
            return step
    return float(d.min())


def round_step(values: np.ndarray) -> float:
    """The largest round step (:func:`nice_step`: 1, 2, 2.5 or 5 x 10^k) of which every difference of the
    sorted ``values`` is a whole multiple, down to a millionth of their span; 0.0 when there is none or
    one value."""
    span = float(values[-1] - values[0])
    if span <= 0:
        return 0.0
    diffs = np.diff(values)
    top = math.floor(math.log10(span))
    for exponent in range(top, top - 7, -1):
        for mantissa in sorted(NICE_MANTISSAS, reverse=True):
            if _whole_multiples(diffs, mantissa * 10.0**exponent):
                return mantissa * 10.0**exponent
    return 0.0


def filter_progression(
    markers: Sequence[ScaleMarker],
    gap_angle: float = math.pi / 2,
    angle_tol: float = math.radians(6.0),  # 9 kept real numbers printed ~7 degrees off their place, but let
    # two of 1,000 held-out renders agree on lines 10x too steep (a dropped decimal point): 505% off
    radii: Sequence[float] | None = None,
    radius_tol: float = 0.2,
    min_markers: int = 3,
) -> ProgressionFit | StageFailure:
    """Keep the markers that form one linear scale, rising clockwise or counter-clockwise; reject the rest.

    ``markers`` need ``angle`` (image angle of the number's projection on the scale circle, see
    :mod:`gauged.types`); ``gap_angle`` is the middle of the gap between the scale's end and start
    (``pi / 2``, the bottom, in the rectified image), from which angles are unwrapped clockwise.
    Every pair of markers proposes a line value(angle); markers within ``angle_tol`` of the line
    are its inliers (a negative number whose sign may be a tick mark is also tried positive). When
    ``radii`` (distance of each marker from the dial centre) are given, inliers must lie within
    ``radius_tol`` (relative) of the pair's radius, which keeps a second, concentric scale apart.
    The best line has the most inliers, then rises clockwise (a tie in numbers stays clockwise: the
    scale stage weighs the signs, :func:`gauged.reader.stages.scale.fit_scales`), then the most
    regular step (whole multiples of a common step, a nice one preferred), then the larger radius,
    then the higher summed OCR score. Numbers falling clockwise are a 0..X scale rising
    counter-clockwise, which prints no minus: a clockwise-only line kept two or three misreads of
    it, or none, and the OCR's quick pass never ended on it. Missing
    numbers are fine: only consistency is required. Fails with ``too_few_numbers`` when fewer than
    ``min_markers`` markers (with angles) are given or agree.
    """
    with_angle = [i for i, m in enumerate(markers) if m.angle is not None]
    rejected: list[tuple[ScaleMarker, str]] = [(m, "no_angle") for m in markers if m.angle is None]
    if len(with_angle) < min_markers:
        return _too_few(f"{len(with_angle)} numbers with angles, need {min_markers}")
    th = np.array([(markers[i].angle - gap_angle) % (2 * math.pi) for i in with_angle])
    vals = np.array([markers[i].value for i in with_angle], float)
    alts = np.where(vals < 0, -vals, vals)  # sign-dropped alternative for negative readings
    score = np.array([markers[i].score for i in with_angle], float)
    rad = None if radii is None else np.array([radii[i] for i in with_angle], float)
    n = len(with_angle)
    best: tuple | None = None
    for i in range(n):
        for j in range(n):
            if th[j] <= th[i]:
                continue
            for vi in {vals[i], alts[i]}:
                for vj in {vals[j], alts[j]}:
                    if vj == vi:
                        continue
                    slope = (vj - vi) / (th[j] - th[i])
                    cand = _inliers(th, vals, alts, vi, th[i], slope, angle_tol)
                    if rad is not None:
                        r0 = 0.5 * (rad[i] + rad[j])
                        cand = {k: v for k, v in cand.items() if abs(rad[k] - r0) <= radius_tol * r0}
                    cand = _unique_values(cand, th, vi, th[i], slope)
                    if len(cand) < 2:
                        continue
                    kv = np.array(list(cand.values()))
                    step = _common_step(kv)
                    q = (kv - kv.min()) / step if step > 0 else kv * 0
                    regular = bool(np.all(np.abs(q - np.round(q)) < 1e-6 * np.maximum(1, q)))
                    key = (len(cand), slope > 0, regular, regular and nice_step(step),
                           0.0 if rad is None else round(float(np.median(rad[list(cand)])), 0),
                           float(score[list(cand)].sum()))
                    if best is None or key > best[0]:
                        best = (key, cand, step, regular)
    if best is None or len(best[1]) < min_markers:
        got = 0 if best is None else len(best[1])
        return _too_few(f"{got} numbers agree on a scale, need {min_markers}")
    _, cand, step, regular = best
    kv = np.array(list(cand.values()))
    kt = th[list(cand)]
    slope, intercept = np.polyfit(kt, kv, 1) if len(set(kt)) > 1 else (0.0, float(kv[0]))
    kept = []
    for k, v in cand.items():
        m = markers[with_angle[k]]
        kept.append(replace(m, value=float(v), inlier=True))
    for k in range(n):
        if k not in cand:
            m = markers[with_angle[k]]
            reason = "off_progression"
            if any(abs(v - vals[k]) < 1e-9 for v in cand.values()):
                reason = "duplicate_value"
            elif rad is not None and not _near_radius(rad, list(cand), k, radius_tol):
                reason = "radius_outlier"
            rejected.append((replace(m, inlier=False), reason))
    kept.sort(key=lambda m: m.value)
    return ProgressionFit(tuple(kept), tuple(rejected), float(slope), float(intercept), float(step),
                          bool(regular and nice_step(step)))


def _inliers(th, vals, alts, v0, t0, slope, tol) -> dict[int, float]:
    """Index -> accepted value for markers whose predicted angle is within ``tol`` of their own."""
    out: dict[int, float] = {}
    for k in range(len(th)):
        errs = [(abs(t0 + (v - v0) / slope - th[k]), v) for v in {vals[k], alts[k]}]
        err, v = min(errs)
        if err <= tol:
            out[k] = float(v)
    return out


def _unique_values(cand: dict[int, float], th, v0, t0, slope) -> dict[int, float]:
    """Keep one marker per value: the one closest in angle to the line's prediction."""
    by_value: dict[float, int] = {}
    for k, v in cand.items():
        key = round(v, 9)
        err = abs(t0 + (v - v0) / slope - th[k])
        if key not in by_value or err < abs(t0 + (v - v0) / slope - th[by_value[key]]):
            by_value[key] = k
    return {k: cand[k] for k in by_value.values()}


def _near_radius(rad: np.ndarray, kept: list[int], k: int, tol: float) -> bool:
    r0 = float(np.median(rad[kept]))
    return abs(rad[k] - r0) <= tol * r0
