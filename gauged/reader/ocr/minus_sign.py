"""Minus signs the recogniser dropped, found in the text's own pixels.

PP-OCR's recogniser often reads "-40" as "40" (and the number net never reads a sign): the dash is
in the detected box, but decoded as nothing. The sign is what tells a clockwise -100..0 scale from a
counter-clockwise 0..100 one (the numbers alone are mirror images, :func:`gauged.reader.stages.scale_direction.
fit_ring`), so reading it wrong sends out a value of the wrong sign, off by up to twice the span.
:func:`with_seen_minus` looks at each number read without a sign: a short horizontal bar of ink,
level with the middle of the digits and left of the first one, in the text's upright line image, is a
minus, and the text gets its "-". The scale stage then weighs the signs as read (``sign_edits``).
"""

from __future__ import annotations

from dataclasses import replace
from typing import Sequence

import cv2
import numpy as np

from gauged.reader.ocr.text import TextBox, crop_quad

BAND = (0.25, 0.75)  # of the digits' extent, top to bottom: where a minus's ink lies
CLEAR = (0.2, 0.8)  # ... and outside this band the columns of a minus hold no ink
BAR_THICK = 0.34  # of the height: the median column of a minus holds ink over at most this (a "4"'s
# diagonal, running into its crossbar, widens column by column)
MIDDLE = (0.3, 0.62)  # ... and where the centre of its ink lies (a "4"'s crossbar lies lower)
BAR_WIDTH = 0.25  # of the digits' height: the least length of a minus
GAP_OR_DIGIT = 0.15  # of the height: how far the columns after the bar may run before a digit starts


def with_seen_minus(texts: Sequence[TextBox], image: np.ndarray) -> list[TextBox]:
    """``texts`` with a "-" put before each number whose line in ``image`` shows a minus the
    recogniser did not read."""
    out = []
    for box in texts:
        text = box.text.strip()
        if text[:1].isdigit() and shows_minus(crop_quad(image, box.quad)):
            box = replace(box, text="-" + text)
        out.append(box)
    return out


def shows_minus(line: np.ndarray) -> bool:
    """Whether the upright text line image (h, w, 3) starts with a minus: read from the left, a run
    of at least :data:`BAR_WIDTH` x height columns whose ink lies only in the middle :data:`BAND`
    (nothing above or below :data:`CLEAR`), before the first column with ink above or below it.

    Scanned by columns rather than by ink components, since a blurred minus runs into its digit.
    A "4"'s crossbar lies lower than a minus and a "7"'s bar at the top; round digits fill their
    leftmost columns from top to bottom."""
    gray = cv2.cvtColor(line, cv2.COLOR_BGR2GRAY) if line.ndim == 3 else line
    if min(gray.shape) < 8:
        return False
    _, dark = cv2.threshold(gray, 0, 255, cv2.THRESH_BINARY_INV + cv2.THRESH_OTSU)
    ink = dark > 0
    if ink.mean() > 0.5:  # light text on a dark face: the ink is the minority
        ink = ~ink
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
