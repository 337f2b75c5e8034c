"""OCR stage: the scale numbers and the unit of a dial, read on its rectified image.

As in Reitsma et al. ("Under pressure", Sec. 3.5) the crop is rectified first: the scale ellipse
becomes a circle (centre ``cx, cy``, radius ``r``) and the gap between the scale's ends is turned to
the bottom, so numbers printed upright are upright. What the pipeline knows is then used to read
more than the paper's one pass did (it failed on 40-57% of images):

- **ring**: text detection runs only on the square around the circle, and only texts whose centre
  lies in the ring ``RING`` (in radii) count as scale numbers;
- **orientation**: a text whose first reading does not parse is read again turned by 180 and +-90
  degrees (radially printed numbers), in the order the circle makes likely; extra rotations run only
  when the first attempt fails;
- **the image's way up**: a dial whose gap is not at the bottom but whose text is printed upright
  stands on its head in the gap-down view; when that view reads too few numbers, the dial is read
  again with the image's down at the bottom;
- **quick pass**: first only the ink at each predicted number centre of the crop model is recognised,
  in one batch, with no text detection; when that gives :data:`QUICK_ENOUGH` numbers of one
  arithmetic progression, only the face inside the scale is searched for the unit and the full pass
  below is skipped (it costs several times more);
- **hints**: in the full pass, predicted number centres that no read number explains get a small
  local detection around the point, or, when even that finds nothing (faint, tiny print), the ink
  blob at the point is recognised;
- **polar fallback**: when fewer than ``POLAR_BELOW`` numbers agree, the ring is unwrapped into a
  strip, where radially printed numbers stand upright, and read too;
- **parsing and filtering**: :mod:`gauged.reader.ocr.numbers` (split boxes merged, distractors refused,
  the arithmetic progression of a linear scale kept) and :mod:`gauged.reader.ocr.units`.

The engine (:class:`gauged.reader.ocr.engine.OcrEngine`) is created once per reader, with a fixed
onnxruntime thread count, from model files inside the installed wheel; nothing is downloaded.
"""

from __future__ import annotations

import math

import cv2
import numpy as np

from gauged.geometry.angles import unwrap, wrap_to_pi
from gauged.geometry.dial_frame import dial_angle
from gauged.reader.ocr.dial_reader import DialTextReader
from gauged.reader.ocr.dial_text import (
    _crop_box,
    _ink_quads,
    _on_main_scale,
    _radial_turn,
    _square,
    _turned,
    keep_progressions,
    scale_markers,
)
from gauged.reader.ocr.hint_numbers import hint_markers
from gauged.reader.ocr.likely_scale import RingText, likely_markers
from gauged.reader.ocr.rectified import _rectified, _View, _view_downs
from gauged.reader.ocr.regions import RING
from gauged.reader.ocr.text import crop_quad
from gauged.reader.ocr.units import (
    PrintedUnit,
    printed_units,
)
from gauged.reader.ocr.minus_sign import shows_minus, with_seen_minus
from gauged.reader.ocr.numbers import printed_decimal
from gauged.reader.stages.crop import Crop
from gauged.reader.stages.ellipse import ScaleArc
from gauged.reader.stages.keypoints import Peaks
from gauged.types import ScaleMarker, StageFailure

STAGE = "ocr"
NO_TEXT, NO_NUMBERS = "no_text", "no_numbers"
REASONS = (NO_TEXT, NO_NUMBERS)


class ScaleTextReader(DialTextReader):
    """Reads scale numbers and units; the pipeline's OCR stage is :meth:`read_markers` (the
    arguments: :class:`~gauged.reader.ocr.dial_reader.DialTextReader`)."""

    # -- the pipeline stage -------------------------------------------------------------------
    def _read_view(self, crop: np.ndarray, arc: ScaleArc, hints: np.ndarray, detail: np.ndarray | None,
                   down: float) -> _View:
        """The texts of the dial rectified with dial angle ``down`` at the bottom (the quick pass,
        then the full pass if that is not enough)."""
        rectified, matrix, circle = _rectified(crop, arc, detail, down)
        gap = float(wrap_to_pi(math.pi / 2 + arc.zero_angle - down))  # where the scale's gap lies in the view
        rhints = None
        if hints is not None and len(hints):
            rhints = cv2.perspectiveTransform(np.asarray(hints, np.float64).reshape(-1, 1, 2), matrix).reshape(-1, 2)
        texts, quick = self.read_quick(rectified, circle, rhints, gap)
        if texts is None:
            texts = self.read_dial(rectified, circle, rhints, known=quick, gap=gap)
        return _View(texts, matrix, circle, gap, rectified)

    def ring_texts(self, crop: np.ndarray, arc: ScaleArc, hints: np.ndarray, detail: np.ndarray | None = None
                   ) -> list[list[RingText]]:
        """Every text region where the main scale's numbers may lie (the ring :data:`RING` outside
        :data:`INNER_SCALE`), per rectified view (:func:`_view_downs`), each read upright and turned
        radially (top outward), whatever it reads: the regions the text detector finds there, and
        the ink at each hint (crop px) that none of them holds. For
        :func:`gauged.reader.ocr.likely_scale.likely_markers`; nothing is filtered by score or parse."""
        views = []
        for down in _view_downs(arc):
            image, matrix, circle = _rectified(crop, arc, detail, down)
            roi, x0, y0 = _square(image, circle[0], circle[1], RING[1] * circle[2])
            quads = [q.quad + np.float32([x0, y0]) for q in self.engine.detect(roi, max_side=self.det_side)] if roi.size else []
            quads = [q for q in quads if _on_main_scale(tuple(q.mean(axis=0)), circle)]
            if hints is not None and len(hints):
                points = cv2.perspectiveTransform(np.asarray(hints, np.float64).reshape(-1, 1, 2), matrix).reshape(-1, 2)
                loose = [tuple(p) for p in points if _on_main_scale(tuple(p), circle)
                         and not any(cv2.pointPolygonTest(q.reshape(-1, 1, 2), (float(p[0]), float(p[1])), False) >= 0 for q in quads)]
                quads += _ink_quads(image, loose, circle[2])
            # each region upright and turned radially (the same line twice when that is upright: read once)
            lines = [crop_quad(image, _turned(q, k)) for q in quads for k in (0, _radial_turn(q, circle))]
            readings = self.engine.recognize(lines)
            texts = []
            for n, quad in enumerate(quads):
                (x0, y0), (x1, y1) = quad.min(axis=0), quad.max(axis=0)
                box = _crop_box(matrix, (float(x0), float(y0), float(x1), float(y1)))
                centre = np.array([[(box[0] + box[2]) / 2, (box[1] + box[3]) / 2]])
                angle = float(unwrap(float(dial_angle(arc.ellipse, centre, arc.centre)[0]), arc.zero_angle))
                radius = math.dist(quad.mean(axis=0), circle[:2]) / circle[2]
                texts.append(RingText(box, angle, radius, {"upright": readings[2 * n], "radial": readings[2 * n + 1]},
                                      {"upright": shows_minus(lines[2 * n]), "radial": shows_minus(lines[2 * n + 1])}))
            views.append(texts)
        return views

    def reread_markers(self, crop: np.ndarray, arc: ScaleArc, hints: np.ndarray, detail: np.ndarray | None = None
                       ) -> list[ScaleMarker] | None:
        """A second look at a dial whose markers gave no scale: the markers of the number grid its
        ring texts most likely print (:func:`gauged.reader.ocr.likely_scale.likely_markers`), or None."""
        views = self.ring_texts(crop, arc, hints, detail)
        start, end = unwrap(arc.start_angle, arc.zero_angle), unwrap(arc.end_angle, arc.zero_angle)
        return likely_markers(views, float(start), float(end), self.engine.log_likelihood)

    @property
    def has_number_net(self) -> bool:
        return self.engine.number_net is not None

    def hint_markers(self, frame: np.ndarray, crop: Crop, arc: ScaleArc, numbers: Peaks) -> list[ScaleMarker] | None:
        """The numbers the number net reads at the crop model's number peaks ``numbers`` (crop px) in
        ``frame`` (:func:`gauged.reader.ocr.hint_numbers.hint_markers`), or None. Needs the number net
        (:attr:`has_number_net`)."""
        return hint_markers(frame, crop, arc, numbers, self.engine.number_net)

    def read_markers_by_number_net(self, crop: np.ndarray, arc: ScaleArc, hints: np.ndarray,
                                   detail: np.ndarray | None = None) -> tuple[list[ScaleMarker], str | None] | StageFailure:
        """:meth:`read_markers` again, every digit line read by the number net too
        (:meth:`OcrEngine.reading_numbers_again`): for a dial whose first markers gave no scale."""
        with self.engine.reading_numbers_again():
            return self.read_markers(crop, arc, hints, detail)

    def read_markers(self, crop: np.ndarray, arc: ScaleArc, hints: np.ndarray, detail: np.ndarray | None = None
                     ) -> tuple[list[ScaleMarker], tuple[PrintedUnit, ...]] | StageFailure:
        """Scale numbers (markers with boxes in ``crop`` pixels) and the units printed on the crop's
        dial (:func:`gauged.reader.ocr.units.printed_units`, best read first).

        ``arc`` is the fitted scale (ellipse, centre, gap), ``hints`` (N, 2) crop px the crop
        model's number centres (may be empty). With ``progression`` and ends found (not inferred), the
        markers are limited to up to two arithmetic progressions (:func:`gauged.reader.ocr.numbers.filter_progression`,
        one per concentric scale) when one is found; otherwise all parsed numbers are returned for the
        scale stage's RANSAC. ``detail``, when given, is the same square region as ``crop`` at a higher
        resolution (any size): the rectified view is sampled from it. Failures: ``no_text``,
        ``no_numbers``.
        """
        self.engine.forget()  # the memo serves this dial's passes only
        downs = _view_downs(arc)
        view = self._read_view(crop, arc, hints, detail, downs[0])
        if len(downs) > 1:
            # Read both ways even when the gap-down view gives a progression: upside down, "100, 200,
            # 300" read "10, 20, 30" with the "0" make one ten times too flat (a held-out render, 53% off).
            other = self._read_view(crop, arc, hints, detail, downs[1])
            if other.agreeing() > view.agreeing():
                view = other
        # The widened lines go to PP-OCR, whose signs count from two numbers on, and to the number net and
        # the minus net, whose evidence counts only summed over the dial's lines: each reads a tick beside
        # a number as its minus now and then (a clockwise 0..400 dial at 173 was read -173 by the number
        # net of the retry).
        net = self.engine.number_net.read if self.engine.number_net is not None else None
        net_odds = self.engine.number_net.minus_log_odds if self.engine.number_net is not None else None
        minus_odds = self.minus_net.log_odds if self.minus_net is not None else None
        texts = with_seen_minus(view.texts, view.image, self.engine.run_recogniser, net, view.circle, net_odds, minus_odds)
        circle, matrix = view.circle, view.matrix
        if not texts:
            return StageFailure(STAGE, NO_TEXT, "no text found on the rectified dial")
        units = printed_units(texts, circle)
        markers = scale_markers(texts, circle)
        if not markers:
            return StageFailure(STAGE, NO_NUMBERS, f"{len(texts)} text(s) read, none a scale number: "
                                + ", ".join(repr(t.text) for t in texts[:6]))
        if not units:
            units = printed_units(self.read_units_closer(view.image, circle), circle)
        # Ends inferred from a notch gap may lie inside a full-circle scale, whose numbers then run on
        # across the gap: unwrapped from it they look off the progression (a real dial indicator lost
        # its 8 and 9), so all of them go on to the scale stage, which tries a full circle.
        if self.progression and not arc.ends_inferred:
            kept = keep_progressions(markers, circle, view.gap)
            # Decimal numbers left out stay on as outliers: on a scale whose other numbers lost their
            # decimal points they are the evidence (gauged.reader.stages.scale, dropped_decimal_point).
            taken = {m.box for m in kept}  # kept markers are copies (their value set): matched by box
            height = float(np.median([m.box[3] - m.box[1] for m in kept]))
            markers = kept + [m for m in markers if m.box not in taken and printed_decimal(m)
                              and m.box[3] - m.box[1] <= 1.5 * height]
        out = [ScaleMarker(m.text, m.value, _crop_box(matrix, m.box), None, None, m.score, m.net_minus) for m in markers]
        return out, units


