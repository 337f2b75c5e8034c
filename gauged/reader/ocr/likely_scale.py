"""A second look at a dial whose numbers gave no scale: the number grid its texts most likely print.

The OCR stage keeps a number only when the recogniser's best string for it parses, and the scale
stage then needs three of them on one line of value against angle. Small or faint print often loses
that: a minus sign or a decimal point dropped, a "20" read "0". But the recogniser gives a
probability to *every* string, and a linear scale leaves few strings possible: numbers evenly
spaced in value at evenly spaced angles. So, as a person reads a worn dial from the numbers that
are clear, this looks for the grid that the texts most likely print:

- every pair of texts whose best strings parse (each also with a minus sign, which is the
  character lost most often) proposes a line of value against dial angle, and each "nice" step
  (1, 2, 2.5 or 5 times a power of ten) that divides both values proposes a grid;
- every text near one of the grid's places (within a quarter of a step, at most
  :data:`PLACE_TOLERANCE`) is asked how likely it is to spell the number printed there
  (:meth:`gauged.reader.ocr.engine.OcrEngine.log_likelihood`, all CTC alignments summed);
- a text *agrees* when that string is nearly as likely as its best one (:data:`MARGIN`) and likely
  in itself (:data:`FLOOR` per character). A grid is taken when at least :data:`MIN_NUMBERS` texts
  agree, the two that proposed it among them, and they are :data:`AGREE_SHARE` of the texts on
  its places: the texts read one way up ("upright") or all radially ("radial"), never a mix, and
  all at one distance from the centre (:data:`RADIUS_BAND`), as one scale's numbers are printed.

A grid may rise clockwise or counter-clockwise. The numbers alone do not tell a ring's mirror grids
apart ("30, 25 ... 0" clockwise print 0..30 rising counter-clockwise, or -30..0 rising clockwise with
every minus unread); the signs seen do: a negative value whose minus went unseen costs the grid
:data:`UNSIGNED`, a positive value on a text that shows a minus :data:`OVERRULED`, so the grid that
explains the texts as read wins.

Two kinds of misreading make false grids, so neither is proposed: whole numbers on a ring where some
text reads as a decimal number (their decimal points were lost: "0.5, 1.0, 1.5" read "5, 10, 15"),
and negative numbers none of which shows its minus sign (unless they end at 0, as a -30..0 scale whose
minus signs all went unread does). The markers of the best grid then go
through the scale stage's own checks (:func:`gauged.reader.stages.scale.fit_scales`) like any others; a
marker keeps its text's own string when that parses to its value ("0.0" stays "0.0", which those
checks read). The pipeline takes this look only after
those checks refused the first reading, so a dial read before is read the same.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

from gauged.reader.ocr.numbers import ParsedNumber, parse_number
from gauged.reader.ocr.text import Recognition
from gauged.types import Box, ScaleMarker, StageFailure

ORIENTATIONS = ("upright", "radial")
NICE_STEPS = tuple(sorted(m * 10.0**e for m in (1.0, 2.0, 2.5, 5.0) for e in range(-3, 5)))
MAX_STEPS = 40  # grid steps between the two texts that propose a grid
MIN_SPACING = math.radians(6.0)  # angle between neighbouring printed numbers
MAX_SPACING = math.radians(120.0)
PLACE_TOLERANCE = math.radians(4.0)  # a text this far from a grid place (or a quarter step) is not on it
MARGIN = 2.0  # nats: an agreeing text spells its number at least e^-2 as likely as its best string
FLOOR = 1.0  # nats per character: ... and at least e^-1 per character in itself
UNSIGNED = 1.0  # nats: a negative number read without its minus sign agrees at this cost
MINUS_SEEN = 3.0  # nats: a text shows a minus sign when its signed spelling is at least e^-3 as likely
OVERRULED = MINUS_SEEN  # nats: a positive number on a text that shows a minus sign counts this much less
# (as much as a faint minus can cost the signed reading: where one is seen, the signed grid is not worse)
MIN_NUMBERS = 4  # agreeing texts a grid needs (the first reading's scale needs 3)
AGREE_SHARE = 0.6  # of the texts on the grid's places
RADIUS_BAND = 0.12  # scale radii: a grid's texts lie this close to its two proposing texts' mean radius

Score = Callable[[Recognition, str], float]


@dataclass(frozen=True)
class RingText:
    """A text region near the scale ring of a dial: ``box`` in crop pixels, ``angle`` its dial angle
    unwrapped from the scale's gap (radians, increasing clockwise like the scale), ``radius`` its
    distance from the dial centre in scale radii, and ``readings`` of it per orientation
    (:data:`ORIENTATIONS`)."""

    box: Box
    angle: float
    radius: float
    readings: dict[str, Recognition]
    minus: dict[str, bool] = field(default_factory=dict)  # per orientation: the line's pixels show a minus
    # (gauged.reader.ocr.minus_sign), read or not


@dataclass
class _Candidate:
    text: RingText
    reading: Recognition
    best: float  # log-likelihood of the reading's own best number string
    parsed: ParsedNumber | None  # the number that string gives
    cache: dict[tuple[float, int], tuple[float, str, bool]] = field(default_factory=dict)
    minus: bool = False  # its pixels show a minus sign (gauged.reader.ocr.minus_sign)


def decimals(step: float) -> int:
    """Decimal places a scale of this step prints: 0 for 5, 1 for 2.5 or 0.5, 2 for 0.25."""
    for places in range(6):
        if abs(round(step, places) - step) < 1e-9:
            return places
    return 6


def spellings(value: float, places: int) -> tuple[list[str], list[str]]:
    """How a dial may print ``value`` at ``places`` decimals: (the signed spellings, the spellings of
    a negative value that lost its minus sign). "0.5" is also ".5" and "0,5"; 0 is also "0". The
    minus is "-" (the engine scores "−" as the same character)."""
    value = 0.0 if abs(value) < 1e-12 else value
    digits = f"{abs(value):.{places}f}"
    forms = {digits, digits.replace(".", ",")}
    if value == 0.0:
        forms.add("0")
    elif digits.startswith("0."):
        forms |= {digits[1:], digits[1:].replace(".", ",")}
    if value >= 0.0:
        return sorted(forms), []
    return sorted("-" + f for f in forms), sorted(forms)


def _likelihood(candidate: _Candidate, value: float, places: int, score: Score) -> tuple[float, str, bool, float]:
    """The log-likelihood of the candidate spelling ``value`` (its likeliest spelling), that spelling,
    whether it was read with its sign (False for a negative value read without its minus), and what
    the sign costs the grid's score: :data:`UNSIGNED` for a minus not seen, :data:`OVERRULED` for a
    positive value on a text that shows one (:data:`MINUS_SEEN`). The two costs keep the mirror
    grids of one ring apart: its texts "30, 25 ... 0" clockwise print 0..30 rising counter-clockwise,
    or -30..0 rising clockwise with every minus unread; the signs seen decide (read, or in the pixels)."""
    key = (round(value, 9), places)
    if key not in candidate.cache:
        signed, unsigned = spellings(value, places)
        options = [(score(candidate.reading, s), s, True) for s in signed]
        options += [(score(candidate.reading, s) - UNSIGNED, "-" + s, False) for s in unsigned]
        likelihood, spelling, with_sign = max(options)
        cost = 0.0 if with_sign else UNSIGNED  # (already in the likelihood of an unsigned spelling)
        if not with_sign and candidate.minus:  # a minus in its pixels that the recogniser dropped
            likelihood, with_sign, cost = likelihood + UNSIGNED, True, 0.0
        if value > 0 and (candidate.minus or max(score(candidate.reading, "-" + s) for s in signed) >= likelihood - MINUS_SEEN):
            cost = OVERRULED
        candidate.cache[key] = (likelihood, spelling, with_sign, cost)
    return candidate.cache[key]


def _parsed(reading: Recognition) -> ParsedNumber | None:
    """The number a reading's best string gives, or None."""
    parsed = parse_number(reading.digits) if reading.digits else None
    return None if parsed is None or isinstance(parsed, StageFailure) or parsed.fragment else parsed


def _anchors(candidates: Sequence[_Candidate]) -> list[tuple[int, float]]:
    """(candidate index, value) of every best string that parses, and of its negative."""
    out = set()
    for index, candidate in enumerate(candidates):
        if candidate.parsed is not None:
            out.add((index, candidate.parsed.value))
            if candidate.parsed.value > 0:
                out.add((index, -candidate.parsed.value))
    return sorted(out)


def _grid_markers(candidates: Sequence[_Candidate], first: tuple[int, float], second: tuple[int, float],
                  start: float, end: float, score: Score, decimal_seen: bool):
    """The best grid through two anchors: ((agreeing count, summed margin), markers) or None.
    ``decimal_seen``: some text reads as a decimal number, so a grid of whole numbers is not proposed."""
    (i, vi), (j, vj) = first, second
    ai, aj = candidates[i].text.angle, candidates[j].text.angle
    radius = (candidates[i].text.radius + candidates[j].text.radius) / 2
    if abs(candidates[i].text.radius - candidates[j].text.radius) > RADIUS_BAND:
        return None
    slope = (vj - vi) / (aj - ai)  # value per radian
    best = None
    for step in NICE_STEPS:
        steps = (vj - vi) / step
        if abs(steps - round(steps)) > 1e-6 or not 1 <= round(steps) <= MAX_STEPS or abs(vi / step - round(vi / step)) > 1e-6:
            continue
        spacing = step / slope  # negative on a scale rising counter-clockwise
        if not MIN_SPACING <= abs(spacing) <= MAX_SPACING:
            continue
        places = decimals(step)
        if places == 0 and decimal_seen:
            continue
        tolerance = min(0.25 * abs(spacing), PLACE_TOLERANCE)
        on_places, agreeing = 0, []
        for k, candidate in enumerate(candidates):
            angle = candidate.text.angle
            place = (angle - ai) / spacing
            if (abs(place - round(place)) * abs(spacing) > tolerance or not start - abs(spacing) / 2 <= angle <= end + abs(spacing) / 2
                    or abs(candidate.text.radius - radius) > RADIUS_BAND):
                continue
            on_places += 1
            value = vi + round(place) * step
            likelihood, spelling, signed, cost = _likelihood(candidate, value, places, score)
            floor = -FLOOR * len(spelling)
            if likelihood >= candidate.best - MARGIN and likelihood >= floor:
                agreeing.append((k, value, spelling, likelihood - (cost if signed else 0.0) - max(candidate.best, floor), signed))
        indices = {a[0] for a in agreeing}
        values = [a[1] for a in agreeing]
        if i not in indices or j not in indices or len(set(values)) < len(values):
            continue
        if any(v < 0 for v in values) and not any(a[1] < 0 and a[4] for a in agreeing) and max(values) != 0.0:
            continue  # negative numbers, not one minus sign seen, and not a scale of negatives up to 0
        if len(agreeing) < AGREE_SHARE * on_places:
            continue
        key = (len(agreeing), sum(a[3] for a in agreeing))
        if best is None or key > best[0]:
            # a negative value whose minus no one saw keeps the text as read, unsigned: the scale stage
            # counts the sign it adds against the grid (gauged.reader.stages.scale.sign_edits)
            markers = [ScaleMarker(_own_text(candidates[k], value, spelling if signed else spelling.lstrip("-")),
                                   float(value), candidates[k].text.box)
                       for k, value, spelling, _, signed in agreeing]
            best = (key, markers)
    return best


def _own_text(candidate: _Candidate, value: float, spelling: str) -> str:
    """The reading's own string when it parses to ``value``, else the grid's spelling of it."""
    parsed = candidate.parsed
    return candidate.reading.digits if parsed is not None and abs(parsed.value - value) < 1e-9 else spelling


def likely_markers(views: Sequence[Sequence[RingText]], start: float, end: float, score: Score
                   ) -> list[ScaleMarker] | None:
    """The markers of the likeliest number grid (see the module docstring), or None.

    ``views`` are the texts of one dial read in one or more rectified views (a grid is made of one
    view's texts); ``start``/``end`` the scale's end angles unwrapped like the texts' angles;
    ``score`` gives a reading's log-likelihood of a string.
    """
    best = None
    for texts in views:
        for orientation in ORIENTATIONS:
            candidates = []
            for text in texts:
                reading = text.readings.get(orientation)
                if reading is not None:
                    own = score(reading, reading.digits) if reading.digits else -math.inf
                    candidates.append(_Candidate(text, reading, own, _parsed(reading), minus=text.minus.get(orientation, False)))
            anchors = _anchors(candidates)
            decimal_seen = any(c.parsed is not None and c.parsed.decimals > 0 for c in candidates)
            for first in anchors:
                for second in anchors:
                    if (first[0] == second[0] or second[1] <= first[1]
                            or candidates[second[0]].text.angle == candidates[first[0]].text.angle):
                        continue  # a grid rises clockwise or counter-clockwise, whichever its texts say
                    found = _grid_markers(candidates, first, second, start, end, score, decimal_seen)
                    if found is not None and (best is None or found[0] > best[0]):
                        best = found
    if best is None or best[0][0] < MIN_NUMBERS:
        return None
    return best[1]
