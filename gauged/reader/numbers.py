"""Parse OCR text into scale numbers and units, robustly and conservatively.

Numbers: decimals with '.' or ',', negative signs (also unicode minus and dashes), a leading 0 read as
O/o, 1 read as l/I, 5 as S, 8 as B when the rest is numeric. Rejected: long digit runs (serial
numbers), text with letters left over (brands, "EN 837"), accuracy classes written as "CL 1.6".
Units: matched against a vocabulary after normalising common OCR confusions.
"""

from __future__ import annotations

import re

_MINUS = "-−–—~‐"
_CONFUSIONS = str.maketrans({"O": "0", "o": "0", "D": "0", "Q": "0", "l": "1", "I": "1", "i": "1", "|": "1",
                             "S": "5", "s": "5", "B": "8", "Z": "2", "z": "2", "G": "6", "g": "9"})
_CONFUSABLE = frozenset("OoDQlIi|SsBZzGg")
_NUMBER = re.compile(r"^-?(\d{1,5}([.,]\d{1,3})?|[.,]\d{1,3})$")

UNITS = {
    "bar": "bar", "mbar": "mbar", "kpa": "kPa", "mpa": "MPa", "pa": "Pa", "psi": "psi", "inhg": "inHg",
    "mmhg": "mmHg", "inh2o": "inH2O", "mmh2o": "mmH2O", "kg/cm2": "kg/cm2", "kgf/cm2": "kg/cm2", "kg/cm": "kg/cm2",
    "kgf/cm": "kg/cm2", "°c": "degC", "℃": "degC", "degc": "degC", "c": "degC", "°f": "degF", "℉": "degF",
    "degf": "degF", "f": "degF", "%": "%", "a": "A", "v": "V", "bar/psi": "bar",
}


def parse_number(text: str) -> float | None:
    """The value of a scale number read as ``text``, or None when it is not one.

    >>> [parse_number(t) for t in ("1,6", "-30", "−1", "O.25", "l0", "160", "SN48213", "CL 1.6", "bar")]
    [1.6, -30.0, -1.0, 0.25, 10.0, 160.0, None, None, None]
    """
    cleaned = text.strip().replace(" ", "")
    if not cleaned or len(cleaned) > 7:
        return None
    if cleaned[0] in _MINUS:
        cleaned = "-" + cleaned[1:]
    body = cleaned[1:] if cleaned.startswith("-") else cleaned
    digits = sum(ch.isdigit() for ch in body)
    letters = sum(ch in _CONFUSABLE for ch in body)
    if any(not (ch.isdigit() or ch in _CONFUSABLE or ch in ".,") for ch in body):
        return None  # a letter no digit is misread as: a word, a unit, a serial number
    if digits == 0 and body not in ("O", "o"):
        return None  # only a lone O passes as a misread 0
    if letters > digits + 1:
        return None
    body = body.translate(_CONFUSIONS)
    candidate = ("-" if cleaned.startswith("-") else "") + body
    if not _NUMBER.match(candidate):
        return None
    value = float(candidate.replace(",", "."))
    return value


def parse_unit(text: str) -> str | None:
    """Canonical unit of ``text`` when it names one (``"KPa"`` -> ``"kPa"``, ``"°C"`` -> ``"degC"``)."""
    key = text.strip().lower().replace(" ", "").replace("²", "2").replace("º", "°").replace("0c", "°c")
    key = key.strip("()[].,:")
    if len(key) == 1 and key not in ("%", "℃", "℉"):
        return None  # a lone C or F is too often a misread fragment; only accept it spelled out
    return UNITS.get(key)
