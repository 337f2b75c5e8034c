"""Minus signs the recogniser dropped, found in the text's own pixels.

PP-OCR's recogniser often reads "-40" as "40": the dash is
in the detected box, but decoded as nothing. The sign is what tells a clockwise -100..0 scale from a
counter-clockwise 0..100 one (the numbers alone are mirror images, :func:`gauged.reader.stages.scale_direction.
fit_ring`), so reading it wrong sends out a value of the wrong sign, off by up to twice the span.
:func:`with_seen_minus` looks at each number read without a sign: a short horizontal bar of ink,
level with the middle of the digits and left of the first one, in the text's upright line image, is a
minus, and the text gets its "-". The recogniser reads the line again widened left (the detector's box
often starts at the first digit); and the number net and the minus net, which see faint minus signs
PP-OCR drops, weigh the widened lines of every unsigned number, their signs counted only when the
dial's evidence is that of a scale of negatives (:func:`summed_minus_signs`; without the minus net,
the number net's strings by :func:`scale_of_negatives`). The scale stage then weighs the signs as read
(``sign_edits``).
"""

from __future__ import annotations

import math
import re
from collections.abc import Callable
from dataclasses import replace
from typing import Sequence

import cv2
import numpy as np

from gauged.reader.ocr.text import Recognition, TextBox, crop_quad

NetOdds = Callable[[list[np.ndarray], list[str]], np.ndarray]  # lines, their digits -> log-odds of a minus first
MinusOdds = Callable[[list[np.ndarray]], np.ndarray]  # lines -> log-odds of a minus first

BAND = (0.25, 0.75)  # of the digits' extent, top to bottom: where a minus's ink lies
CLEAR = (0.2, 0.8)  # ... and outside this band the columns of a minus hold no ink
BAR_THICK = 0.34  # of the height: the median column of a minus holds ink over at most this (a "4"'s
# diagonal, running into its crossbar, widens column by column)
MIDDLE = (0.3, 0.62)  # ... and where the centre of its ink lies (a "4"'s crossbar lies lower)
BAR_WIDTH = 0.25  # of the digits' height: the least length of a minus
GAP_OR_DIGIT = 0.15  # of the height: how far the columns after the bar may run before a digit starts
LEFT_MARGIN = 0.4  # of the box's height: how far left of a detected box its line is read again. The text
# detector's box often ends at the first digit and leaves a small, faint minus outside it.
MIN_WIDENED = 2  # numbers that must show a minus in their widened lines for any of those signs to count
NET_SHARE = 0.75  # of a dial's unsigned numbers other than 0: how many the number net must read a minus
# before in their widened lines for its signs to count. The net reads the faint, thin minus signs PP-OCR
# decodes as nothing (a -30..0 dial's "30, 20, 15, 25, 5" all read "-" by the net, none by PP-OCR), but
# also a tick or a blur beside a number as its minus: on 300 + 300 held-out renders, 54 of 1,628
# positive numbers got one. At 0.5 two more counter-clockwise dials were read right, but 0..1 and
# 0..0.25 dials with two such signs among three or four numbers were read negative (held-out, clockwise)
TICKS_BEFORE = 0.7  # cosine between a number's "before" (left of its text) and the way to the scale ring
# above which the ring's ticks stand level with its digits, just before them: the net's minus there is
# no evidence: the number is not read, and counts as one without a minus ("0.05, 0.10" inside the ring at
# 9 o'clock of a 0..0.25 dial were read "-0.05, -0.10" on the ring's ticks, and with "0.25" beside them
# made a scale of negatives; "0.2, 0.4" of a 0..1 dial were read "-0.2, -0.4" beside a "1.0" on the ticks)
ODDS_CLIP = 3.0  # each net's log-odds of a minus before a number, clipped to +-this: no one line, however
# sure a net is of it, signs a dial on its own
SIGN_ODDS = 2.0  # the sum over a dial's lines of their evidence above which its leaning lines are signed.
# On 400 + 400 dev renders (seed 7,000,000, cw and ccw), of the dials with two or more lines weighed, 7
# of 15 scales of negatives are signed and none of 511 positive ones, at any sum from 0 to 3 (the number
# net's strings with NET_SHARE: 4 of the 15, and 2 positive dials; bench/investigations/minus_evidence.py).
# The sum of the two nets' odds in place of the lesser signed 9 of the 15 there and one positive dial, and
# held-out positive dials of two or three lines
# where one net alone was sure of a minus ("0.2, 0.4" of a 0..1 dial: the number net 5.6 and 4.5, the
# minus net 1.1 and -0.8)
UNSIGNED_NUMBER = re.compile(r"\d+(?:[.,]\d+)?")


def with_seen_minus(texts: Sequence[TextBox], image: np.ndarray,
                    read: Callable[[list[np.ndarray]], list[Recognition]] | None = None,
                    net: Callable[[list[np.ndarray]], list[str]] | None = None,
                    circle: tuple[float, float, float] | None = None,
                    net_odds: NetOdds | None = None, minus_odds: MinusOdds | None = None) -> list[TextBox]:
    """``texts`` with a "-" put before each number whose line in ``image`` shows a minus the
    recogniser did not read: in its pixels (:func:`shows_minus`), or, with ``read`` (the
    recogniser), in the line widened left (:func:`minus_left_of_box`), or, with ``net`` (the number
    net) and ``circle`` (the scale ring in ``image``, cx, cy, r), in the widened lines of a scale of
    negatives (:func:`number_net_reads`, :func:`scale_of_negatives`). Every box before which the net
    read a minus (with the minus net: whose evidence leans to one) gets ``net_minus``, its signs counted or not: the evidence term
    ``net_minus_against`` (:mod:`gauged.reader.evidence`). With ``net_odds`` (the number net's
    log-odds of a minus) and ``minus_odds`` (the minus net, :mod:`gauged.reader.ocr.minus_net`), the
    two nets' evidence summed over the dial tells those signs instead (:func:`summed_minus_signs`)."""
    widened = minus_left_of_box(texts, image, read) if read else set()
    if circle is not None and net_odds is not None and minus_odds is not None:
        signed, leaning = summed_minus_signs(texts, image, net_odds, minus_odds, circle)
    elif circle is not None and net is not None:
        net_reads = number_net_reads(texts, image, net, circle)
        signed = scale_of_negatives(texts, net_reads)
        leaning = {k for k, read_as in net_reads.items() if read_as.startswith("-")}
    else:
        signed, leaning = set(), set()
    widened |= signed
    out = []
    for k, box in enumerate(texts):
        text = box.text.strip()
        if k in leaning:
            box = replace(box, net_minus=True)
        if text[:1].isdigit() and (k in widened or shows_minus(crop_quad(image, box.quad))):
            box = replace(box, text="-" + text)
        out.append(box)
    return out


def minus_left_of_box(texts: Sequence[TextBox], image: np.ndarray,
                      read: Callable[[list[np.ndarray]], list[Recognition]]) -> set[int]:
    """Indices of the unsigned numbers of ``texts`` that ``read`` (the recogniser) reads as the same
    digits after a minus once their line is widened left by :data:`LEFT_MARGIN` of its height;
    only lines with ink there (:func:`ink_before`) are read again. The text detector's box often
    starts at the first digit and leaves a small, faint minus outside.

    A tick beside a number reads as a minus too, so the minus signs count only when
    :data:`MIN_WIDENED` numbers show one (a scale prints its negative numbers by the several), and
    a text that holds anything but digits and a decimal point (a tick read "15-") is not read again."""
    unsigned = [k for k, box in enumerate(texts) if UNSIGNED_NUMBER.fullmatch(box.text.strip())]
    lines = {k: crop_quad(image, left_extended(texts[k].quad, LEFT_MARGIN)) for k in unsigned}
    inked = [k for k, line in lines.items() if ink_before(line, LEFT_MARGIN)]
    if len(inked) < MIN_WIDENED:
        return set()
    widened = read([lines[k] for k in inked])
    found = {k for k, rec in zip(inked, widened, strict=True) if rec.digits.replace("−", "-") == "-" + texts[k].text.strip()}
    return found if len(found) >= MIN_WIDENED else set()


def number_net_reads(texts: Sequence[TextBox], image: np.ndarray, net: Callable[[list[np.ndarray]], list[str]],
                     circle: tuple[float, float, float]) -> dict[int, str]:
    """``net``'s reading of the line of each unsigned number of ``texts`` other than 0, widened left
    by :data:`LEFT_MARGIN` of its height, by index; none unless :data:`MIN_WIDENED` or more are read.
    Numbers whose line starts toward the scale ring ``circle`` (:func:`faces_ticks`) are not read."""
    readable = readable_numbers(texts, circle)
    if len(readable) < MIN_WIDENED:
        return {}
    reads = net([crop_quad(image, left_extended(texts[k].quad, LEFT_MARGIN)) for k in readable])
    return dict(zip(readable, reads, strict=True))


def summed_minus_signs(texts: Sequence[TextBox], image: np.ndarray, net_odds: NetOdds, minus_odds: MinusOdds,
                       circle: tuple[float, float, float]) -> tuple[set[int], set[int]]:
    """(the numbers signed, the numbers whose evidence leans to a minus) of the unsigned numbers of
    ``texts`` other than 0 whose lines do not face the ticks, read widened left by :data:`LEFT_MARGIN`.

    Each line's evidence is the lesser of two log-odds of a minus before its digits, each clipped to
    :data:`ODDS_CLIP`: the number net's (``net_odds``, its CTC columns, trained on whole numbers) and
    the minus net's (``minus_odds``, trained on these lines alone). Each net alone reads a tick or a
    blur beside a number as its minus now and then, rarely both at once. A scale of negatives prints
    its minus on all of its numbers but 0, so the dial's evidence is the sum over its lines: the lines
    whose own evidence leans to a minus are signed when that sum passes :data:`SIGN_ODDS` and at least
    :data:`MIN_WIDENED` lines lean so. A tick or blur beside one number does not sign a dial."""
    readable = readable_numbers(texts, circle)
    if len(readable) < MIN_WIDENED:
        return set(), set()
    lines = [crop_quad(image, left_extended(texts[k].quad, LEFT_MARGIN)) for k in readable]
    digits = [texts[k].text.strip() for k in readable]
    each = np.minimum(np.clip(np.asarray(minus_odds(lines), np.float64), -ODDS_CLIP, ODDS_CLIP),
                      np.clip(np.asarray(net_odds(lines, digits), np.float64), -ODDS_CLIP, ODDS_CLIP))
    leaning = {k for k, e in zip(readable, each, strict=True) if e > 0}
    sure = float(each.sum()) > SIGN_ODDS and len(leaning) >= MIN_WIDENED
    return (leaning if sure else set()), leaning


def scale_of_negatives(texts: Sequence[TextBox], reads: dict[int, str]) -> set[int]:
    """Indices of the numbers the number net ``reads`` as their digits after a minus; none unless they
    are :data:`MIN_WIDENED` or more and :data:`NET_SHARE` of the unsigned numbers of ``texts`` other
    than 0 (a scale of negatives prints its minus signs on all of its numbers but 0; a tick beside a
    number reads as its minus on a few). The numbers the net did not read count among the numbers,
    never among the signs."""
    found = {k for k, text in reads.items() if text == "-" + texts[k].text.strip()}
    return found if len(found) >= max(MIN_WIDENED, NET_SHARE * len(unsigned_numbers(texts))) else set()


def unsigned_numbers(texts: Sequence[TextBox]) -> list[int]:
    """Indices of the numbers of ``texts`` read without a sign, other than 0: those a minus may be missing from."""
    return [k for k, box in enumerate(texts) if UNSIGNED_NUMBER.fullmatch(box.text.strip())
            and float(box.text.strip().replace(",", ".")) != 0]


def readable_numbers(texts: Sequence[TextBox], circle: tuple[float, float, float]) -> list[int]:
    """:func:`unsigned_numbers` whose lines do not face the ticks of the scale ring ``circle``
    (:func:`faces_ticks`): the ones the nets weigh."""
    return [k for k in unsigned_numbers(texts) if not faces_ticks(texts[k].quad, circle)]


def faces_ticks(quad: np.ndarray, circle: tuple[float, float, float]) -> bool:
    """Whether the text quad's "before" (against its reading direction) points at the scale ring
    ``circle`` (cx, cy, r) within :data:`TICKS_BEFORE`: outward for a number inside the ring,
    inward for one outside, where the ring's ticks run level with the digits."""
    q = np.asarray(quad, np.float64)
    before = q[0] - q[1]
    centre = q.mean(axis=0) - np.asarray(circle[:2], np.float64)
    distance, length = float(np.linalg.norm(centre)), float(np.linalg.norm(before))
    if distance < 1e-6 or length < 1e-6:
        return False
    toward_ring = centre / distance if distance < circle[2] else -centre / distance
    return float(before @ toward_ring) / length > TICKS_BEFORE


def ink_before(line: np.ndarray, margin: float) -> bool:
    """Whether the first ``margin`` x height columns of the upright line image hold any ink level
    with the middle of the line (:data:`BAND`): the cheap test before a widened line is read again."""
    h, w = line.shape[:2]
    width = int(round(margin * h))
    if h < 8 or width < 2 or w <= width:
        return False
    ink = _ink(line)
    band = ink[int(BAND[0] * h):int(math.ceil(BAND[1] * h)), :width]
    return int(band.any(axis=0).sum()) >= max(2, int(0.1 * h))


def _ink(line: np.ndarray) -> np.ndarray:
    """(h, w) bool: the ink of a text line image, the darker side of its Otsu threshold, or the
    lighter where that is most of the line (light text on a dark face: the ink is the minority)."""
    gray = cv2.cvtColor(line, cv2.COLOR_BGR2GRAY) if line.ndim == 3 else line
    _, dark = cv2.threshold(gray, 0, 255, cv2.THRESH_BINARY_INV + cv2.THRESH_OTSU)
    ink = dark > 0
    return ~ink if ink.mean() > 0.5 else ink


def left_extended(quad: np.ndarray, margin: float) -> np.ndarray:
    """The text quad (top-left, top-right, bottom-right, bottom-left) with its left edge moved out
    along the text's direction by ``margin`` times its height."""
    q = np.asarray(quad, np.float32)
    along = q[1] - q[0]
    along = along / max(float(np.linalg.norm(along)), 1e-6)
    shift = along * margin * float(np.linalg.norm(q[3] - q[0]))
    return np.float32([q[0] - shift, q[1], q[2], q[3] - shift])


def shows_minus(line: np.ndarray) -> bool:
    """Whether the upright text line image (h, w, 3) starts with a minus: read from the left, a run
    of at least :data:`BAR_WIDTH` x height columns whose ink lies only in the middle :data:`BAND`
    (nothing above or below :data:`CLEAR`), before the first column with ink above or below it.

    Scanned by columns rather than by ink components, since a blurred minus runs into its digit.
    A "4"'s crossbar lies lower than a minus and a "7"'s bar at the top; round digits fill their
    leftmost columns from top to bottom."""
    if min(line.shape[:2]) < 8:
        return False
    ink = _ink(line)
    rows = ink.sum(axis=1)
    inked = np.flatnonzero(rows >= 0.15 * rows.max()) if rows.max() else np.zeros(0, int)
    if len(inked) < 6:
        return False
    top, bottom = int(inked[0]), int(inked[-1]) + 1
    height = bottom - top
    y = (np.arange(ink.shape[0]) - top) / height
    band = ink[(y >= BAND[0]) & (y <= BAND[1])].any(axis=0)
    outside = ink[(y < CLEAR[0]) | (y > CLEAR[1])].any(axis=0)
    columns = np.flatnonzero(band | outside)
    if not len(columns):
        return False
    first = int(columns[0])
    for x in range(first, ink.shape[1]):
        if outside[x]:
            break
    else:
        return False  # no digit after the bar
    bar = ink[:, first:x]
    run = int(bar.any(axis=0).sum())
    if run < BAR_WIDTH * height:
        return False
    filled = [np.flatnonzero(col) for col in bar.T if col.any()]
    if np.median([rows[-1] - rows[0] + 1 for rows in filled]) > BAR_THICK * height:
        return False
    centre = (np.nonzero(bar)[0].mean() - top) / height
    return MIDDLE[0] <= centre <= MIDDLE[1]
