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
from collections.abc import Callable, Sequence
from pathlib import Path

import cv2
import numpy as np

from gauged.geometry.angles import unwrap, wrap_to_pi
from gauged.geometry.dial_frame import dial_angle
from gauged.reader.ocr.dial_text import (
    Circle,
    _accepts,
    _crop_box,
    _dedupe,
    _explains,
    _hint_window,
    _in_ring,
    _ink_quads,
    _inks,
    _main_scale,
    _maybe_turned,
    _on_main_scale,
    _progression_size,
    _radial_turn,
    _ring_texts,
    _split_spaced,
    _square,
    _turned,
    _up,
    keep_progressions,
    scale_markers,
)
from gauged.reader.ocr.engine import DEFAULT_MODEL_PACKAGE, OcrEngine
from gauged.reader.ocr.hint_numbers import hint_markers
from gauged.reader.ocr.likely_scale import RingText, likely_markers
from gauged.reader.ocr.number_net import NumberNet
from gauged.reader.ocr.numbers import parse_number
from gauged.reader.ocr.rectified import _rectified, _View, _view_downs
from gauged.reader.ocr.regions import RING, polar_strip
from gauged.reader.ocr.text import TextBox, crop_quad
from gauged.reader.ocr.units import (
    PrintedUnit,
    names_unit,
    normalise,
    printed_units,
)
from gauged.reader.stages.crop import Crop
from gauged.reader.stages.ellipse import ScaleArc
from gauged.reader.stages.keypoints import Peaks
from gauged.types import ScaleMarker, StageFailure

STAGE = "ocr"
NO_TEXT, NO_NUMBERS = "no_text", "no_numbers"
REASONS = (NO_TEXT, NO_NUMBERS)
TURNED_MIN_SCORE = 0.9  # a reading found only after turning the text must be this confident
POLAR_BELOW = 4  # read the unwrapped ring too when the first pass gives fewer progression numbers
LOCAL_DETECTIONS = 1  # hints still unexplained after the ink reads that get a text detection of their own (2
# refused the same 135 of 300 dev renders and 6 of 21 real photos for 59 ms more CPU per read; 0 lost a real one)
CLOSER_RADII = 0.75  # scale radii: half the side of the face's centre square read again for a unit
CLOSER_SIDE = 480  # px the detector sees that square at (the ring square, 1.45 radii, is seen at 384)
CLOSER_MIN_MATCH = 0.9  # the closer look takes spelled units only: its lone letters ("A", "C", "F" of logos and
# strokes) named the wrong unit on 9 of the five synthetic sets' readings (session 22); nor a lone "Pa", the
# tail of a "kPa" or "MPa" whose first letter it did not read (2 more)
QUICK_ENOUGH = 4  # numbers of one progression read at the hints alone that end the quick pass
POLAR_DETECT_SCALE = 0.75  # of the strip's size for its text detection: the same 130 of 300 dev renders and 7 of 21
# real photos refused as at full size, for about half its cost (57 -> ~30 ms on an 875 px strip)
OUTER_SCALE = 1.12  # scale radii: two numbers beyond this that the hints missed send the quick pass on


class ScaleTextReader:
    """Reads scale numbers and units; the pipeline's OCR stage is :meth:`read_markers`.

    ``threads`` is onnxruntime's intra-op thread count, ``models`` the wheel whose ONNX files are
    used (:data:`gauged.reader.ocr.engine.MODEL_SETS`), ``min_score`` the recogniser score under
    which a reading is tried in other orientations and, if still under, dropped. ``det_side`` is the
    detector's input side in pixels for the ring around the circle. ``int8_detector`` is the int8
    copy of the text detector to run instead of the float one (:class:`OcrEngine`); ``number_net`` the
    number net's ONNX file (:mod:`gauged.reader.ocr.number_net`) that reads digit lines again.
    """

    def __init__(self, threads: int = 2, models: str = DEFAULT_MODEL_PACKAGE, min_score: float = 0.5,
                 det_side: int = 384, use_hints: bool = True, progression: bool = True,
                 polar_fallback: bool = True, quick: bool = True, int8_detector: Path | None = None,
                 number_net: Path | None = None) -> None:
        self.engine = OcrEngine(threads=threads, package=models, int8_detector=int8_detector,
                                number_net=NumberNet(number_net, threads) if number_net is not None else None)
        self.min_score = min_score
        self.det_side = det_side
        self.use_hints = use_hints
        self.progression = progression
        self.polar_fallback = polar_fallback
        self.quick = quick

    # -- reading text -------------------------------------------------------------------------
    def read(self, image_bgr: np.ndarray, circle: Circle | None = None,
             hints: np.ndarray | None = None, known: Sequence[TextBox] = ()) -> list[TextBox]:
        """Every text read on (H, W, 3) uint8 BGR ``image_bgr``, quads in its pixel coordinates.

        With ``circle = (cx, cy, r)`` (px) detection is limited to the square around the ring
        :data:`RING` and texts whose centres fall outside the ring are dropped, except units: a dial
        prints its unit anywhere on the face, often nearer the centre than the ring. ``hints`` (N, 2) px
        are predicted number centres: each one no read number explains is read again
        (:meth:`_read_hints`). ``known`` are texts already read (the quick pass's), kept and not re-read.
        """
        if image_bgr.ndim != 3 or image_bgr.shape[2] != 3:
            raise ValueError(f"expected an (H, W, 3) BGR image, got shape {image_bgr.shape}")
        x0 = y0 = 0
        roi = image_bgr
        if circle is not None:
            roi, x0, y0 = _square(image_bgr, circle[0], circle[1], RING[1] * circle[2])
        boxes: list[TextBox] = []
        if roi.size:
            quads = [q.quad + np.float32([x0, y0]) for q in self.engine.detect(roi, max_side=self.det_side)]
            boxes = self._recognise(image_bgr, quads, circle)
        if circle is not None:
            units = [b for b in boxes if not _in_ring(b.center, circle) and names_unit(b.text)]
            boxes = _ring_texts(boxes, circle) + units
        boxes += list(known)
        if hints is not None and len(hints) and circle is not None and self.use_hints:
            boxes += self._read_hints(image_bgr, np.asarray(hints, float), boxes, circle)
        return _split_spaced(_dedupe(boxes))

    def _recognise(self, image: np.ndarray, quads: Sequence[np.ndarray], circle: Circle | None) -> list[TextBox]:
        """Recognise each quad; re-read the ones that fail in the other orientations."""
        if not quads:
            return []
        first = self.engine.recognize([crop_quad(image, q) for q in quads])
        out = []
        for quad, rec in zip(quads, first, strict=True):
            best = TextBox(rec.text, rec.score, np.asarray(quad, np.float32), rec.digits, rec.digits_score)
            if not _accepts(best, self.min_score) and _maybe_turned(best):
                best = self._reorient(image, best, circle)
            if best.text and best.score >= self.min_score:
                out.append(best)
        return out

    def _reorient(self, image: np.ndarray, box: TextBox, circle: Circle | None) -> TextBox:
        """Read ``box`` turned by 180 and +-90 degrees, the likeliest first; stop at an accepted one."""
        order = [2, 1, 3]
        if circle is not None:
            c = np.array(box.center) - np.array(circle[:2])
            outward = c / max(float(np.linalg.norm(c)), 1e-9)
            ups = {k: _up(_turned(box.quad, k)) for k in order}
            order.sort(key=lambda k: -max(float(ups[k] @ np.array([0.0, -1.0])), float(ups[k] @ outward)))
        for k in order:
            quad = _turned(box.quad, k)
            rec = self.engine.recognize([crop_quad(image, quad)])[0]
            cand = TextBox(rec.text, rec.score, quad, rec.digits, rec.digits_score)
            if _accepts(cand, max(self.min_score, TURNED_MIN_SCORE)):
                return cand
        return box

    def _read_hints(self, image: np.ndarray, hints: np.ndarray, found: list[TextBox], circle: Circle) -> list[TextBox]:
        """Read the numbers at hints that no read number explains: first the ink at each one, all
        recognised in one batch; then, for up to :data:`LOCAL_DETECTIONS` hints still unexplained, a
        text detection in a window around it (a detection costs as much as a dozen recognitions)."""
        r = circle[2]
        numbers = [b for b in found if parse_number(b.text)]
        pending = [(hx, hy) for hx, hy in hints
                   if _in_ring((hx, hy), circle) and not any(_explains(b, (hx, hy), 0.12 * r) for b in numbers)]
        if not pending:
            return []
        out = [b for b in self._recognise(image, _ink_quads(image, pending, r), circle) if parse_number(b.text)]
        still = [p for p in pending if not any(_explains(b, p, 0.12 * r) for b in out)]
        for hx, hy in still[:LOCAL_DETECTIONS]:
            window = _hint_window(image, hx, hy, r)
            if window is None:
                continue
            win, x0, y0 = window
            side = int(min(320, max(160, 32 * round(max(win.shape[:2]) * 2 / 32))))
            found_quads = [q.quad + np.float32([x0, y0]) for q in self.engine.detect(win, max_side=side)]
            found_quads = [q for q in found_quads if math.dist(q.mean(axis=0), (hx, hy)) < 0.25 * r]
            if found_quads:
                quad = min(found_quads, key=lambda q: math.dist(q.mean(axis=0), (hx, hy)))
                out += [b for b in self._recognise(image, [quad], circle) if parse_number(b.text)]
        return out

    def read_at_hints(self, image_bgr: np.ndarray, hints: np.ndarray, circle: Circle) -> tuple[list[TextBox], bool]:
        """The quick pass: the ink blob at each hint (predicted number centre, px) recognised, all in
        one batch, no text detection. Returns the readings that parse as numbers, and whether one of
        them is a single glyph of a turned number (read alone, the "4" of a "40" is a number too)."""
        in_ring = [(hx, hy) for hx, hy in np.asarray(hints, float).reshape(-1, 2) if _in_ring((hx, hy), circle)]
        inks = _inks(image_bgr, in_ring, circle[2])
        boxes = [b for b in self._recognise(image_bgr, [quad for quad, _ in inks], circle) if parse_number(b.text)]
        numbers = _split_spaced(_dedupe(boxes))
        parts = [quad for quad, turned_part in inks if turned_part]
        return numbers, any(np.array_equal(t.quad, quad) for t in numbers for quad in parts)

    def read_face_texts(self, image_bgr: np.ndarray, circle: Circle, known: Sequence[TextBox]) -> list[TextBox]:
        """After a quick pass: the texts on the whole ring square (one detection) that the quick
        pass's numbers ``known`` do not explain, recognised in one batch (the unit, and any number
        the hints missed)."""
        return self._texts_in_square(image_bgr, circle, RING[1], self.det_side,
                                     lambda q: not any(_explains(b, tuple(q.mean(axis=0)), 0.0) for b in known))

    def read_units_closer(self, image_bgr: np.ndarray, circle: Circle) -> list[TextBox]:
        """The unit texts of the face's centre square (:data:`CLOSER_RADII`) detected at
        :data:`CLOSER_SIDE` px, 2.4 times the ring square's scale: for a dial whose texts named no
        unit, small unit print that detection missed (7 of 30 held-out readings without a unit)."""
        return [t for t in self._texts_in_square(image_bgr, circle, CLOSER_RADII, CLOSER_SIDE)
                if names_unit(t.text, CLOSER_MIN_MATCH) and normalise(t.text) != "pa"]

    def _texts_in_square(self, image_bgr: np.ndarray, circle: Circle, radii: float, side: int,
                         keep: Callable[[np.ndarray], bool] | None = None) -> list[TextBox]:
        """Texts detected in the square of half-side ``radii`` scale radii about the circle's centre, at
        ``side`` px, the quads ``keep`` accepts (all when None) recognised in one batch."""
        roi, x0, y0 = _square(image_bgr, circle[0], circle[1], radii * circle[2])
        if not roi.size:
            return []
        quads = [q.quad + np.float32([x0, y0]) for q in self.engine.detect(roi, max_side=side)]
        quads = [q for q in quads if keep is None or keep(q)]
        if not quads:
            return []
        recs = self.engine.recognize([crop_quad(image_bgr, q) for q in quads])
        return [TextBox(rec.text, rec.score, np.asarray(q, np.float32), rec.digits, rec.digits_score)
                for q, rec in zip(quads, recs, strict=True) if rec.text and rec.score >= self.min_score]

    def read_quick(self, image_bgr: np.ndarray, circle: Circle, hints: np.ndarray | None, gap: float = math.pi / 2
                   ) -> tuple[list[TextBox] | None, list[TextBox]]:
        """The quick pass: ``(numbers and unit, numbers)`` when the hints alone give enough numbers,
        else ``(None, the numbers they gave)`` for the full pass to keep.

        Its numbers must form a progression near the ring, and no other numbers may be printed
        outside the ring: those would be a main scale the crop model did not hint (a degF ring
        around the degC one it did), which only the full pass reads. Nor may one of them be a glyph
        of a turned number read alone (:meth:`read_at_hints`).
        """
        if not self.quick or hints is None or len(hints) < QUICK_ENOUGH:
            return None, []
        numbers, turned_part = self.read_at_hints(image_bgr, hints, circle)
        if turned_part:
            # Glyphs of a turned "30, 40, 50" read "3, 4, 5" agree on a line ten times too flat (synthetic
            # fresh13 000296: 86% off); the full pass reads the detector's turned boxes whole.
            return None, numbers
        # Numbers deep inside the ring belong to an inner, secondary scale: the main scale's numbers
        # were not hinted, so only the full pass can find them.
        near_ring = [t for t in numbers if _main_scale(t, circle)]
        if _progression_size(near_ring, circle, gap) < QUICK_ENOUGH:
            return None, numbers
        others = self.read_face_texts(image_bgr, circle, numbers)
        outside = [t for t in others if parse_number(t.text) and math.dist(t.center, circle[:2]) > OUTER_SCALE * circle[2]]
        if len(outside) >= 2:
            return None, numbers
        # The face's detection also read main-scale numbers the hints' ink missed: they are kept, as
        # the full pass would keep them (an inner scale's numbers are left to the full pass).
        missed = [t for t in _ring_texts(others, circle) if parse_number(t.text) and _main_scale(t, circle)]
        return _dedupe(numbers + missed) + [t for t in others if names_unit(t.text)], numbers

    def read_dial(self, image_bgr: np.ndarray, circle: Circle, hints: np.ndarray | None = None,
                  known: Sequence[TextBox] = (), gap: float = math.pi / 2) -> list[TextBox]:
        """:meth:`read` on a rectified dial, plus :meth:`read_polar`'s numbers when the first pass
        yields fewer than :data:`POLAR_BELOW` numbers of one progression (radially printed scales)."""
        texts = self.read(image_bgr, circle, hints, known)
        if self.polar_fallback and _progression_size(texts, circle, gap) < POLAR_BELOW:
            polar = [b for b in self.read_polar(image_bgr, circle, gap) if parse_number(b.text)]
            texts = _split_spaced(_dedupe(texts + polar))
        return texts

    def read_polar(self, image_bgr: np.ndarray, circle: Circle, gap_angle: float = math.pi / 2) -> list[TextBox]:
        """Texts read on the ring :data:`RING` unwrapped into a strip, quads mapped back to the image.

        The strip's columns run clockwise from ``gap_angle`` (so no scale number is cut at the seam)
        and its rows inward from the outer radius, which makes radially printed numbers (tops
        outward) upright; the strip is ``2 pi 0.8 r`` px long, keeping text near the scale at its
        size. Upright-printed numbers come out turned by their angle, so this complements
        :meth:`read` rather than replacing it.
        """
        strip, to_image = polar_strip(image_bgr, circle, gap_angle)
        h, w = strip.shape[:2]
        quads = [q.quad for q in self.engine.detect(strip, max_side=int(POLAR_DETECT_SCALE * max(w, h)))]
        if not quads:
            return []
        out = []
        for quad, rec in zip(quads, self.engine.recognize([crop_quad(strip, q) for q in quads]), strict=True):
            if rec.text and rec.score >= self.min_score:
                out.append(TextBox(rec.text, rec.score, to_image(quad), rec.digits, rec.digits_score))
        return out

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
                texts.append(RingText(box, angle, radius, {"upright": readings[2 * n], "radial": readings[2 * n + 1]}))
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
            # 300" read "10, 20, 30" with the "0" make one ten times too flat (held-out 000874, 53% off).
            other = self._read_view(crop, arc, hints, detail, downs[1])
            if other.agreeing() > view.agreeing():
                view = other
        texts, circle, matrix = view.texts, view.circle, view.matrix
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
            markers = kept + [m for m in markers if m.box not in taken and m.value != round(m.value)
                              and m.box[3] - m.box[1] <= 1.5 * height]
        out = [ScaleMarker(m.text, m.value, _crop_box(matrix, m.box), None, None, m.score) for m in markers]
        return out, units


