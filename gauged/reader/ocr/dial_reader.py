"""Reading text on a rectified dial (the scale circle ``circle`` known): detection, recognition in
every orientation, the local reads at the crop model's number centres, the unwrapped ring, the unit."""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from pathlib import Path

import numpy as np

from gauged.reader.ocr.dial_text import (
    Circle,
    _accepts,
    _dedupe,
    _explains,
    _hint_window,
    _in_ring,
    _ink_quads,
    _inks,
    _main_scale,
    _maybe_turned,
    _progression_size,
    _ring_texts,
    _split_spaced,
    _square,
    _turned,
    _up,
)
from gauged.reader.ocr.engine import DEFAULT_MODEL_PACKAGE, OcrEngine
from gauged.reader.ocr.minus_net import MinusNet
from gauged.reader.ocr.number_net import NumberNet
from gauged.reader.ocr.numbers import parse_number
from gauged.reader.ocr.regions import RING, polar_strip
from gauged.reader.ocr.text import TextBox, crop_quad
from gauged.reader.ocr.units import (
    names_unit,
    normalise,
)

TURNED_MIN_SCORE = 0.9  # a reading found only after turning the text must be this confident
POLAR_BELOW = 4  # read the unwrapped ring too when the first pass gives fewer progression numbers
LOCAL_DETECTIONS = 1  # hints still unexplained after the ink reads that get a text detection of their own (2
# refused the same 135 of 300 dev renders and 6 of 21 real photos for 59 ms more CPU per read; 0 lost a real one)
CLOSER_RADII = 0.75  # scale radii: half the side of the face's centre square read again for a unit
CLOSER_SIDE = 480  # px the detector sees that square at (the ring square, 1.45 radii, is seen at 384)
CLOSER_MIN_MATCH = 0.9  # the closer look takes spelled units only: its lone letters ("A", "C", "F" of logos and
# strokes) named the wrong unit on 9 of the five synthetic sets' readings; nor a lone "Pa", the
# tail of a "kPa" or "MPa" whose first letter it did not read (2 more)
QUICK_ENOUGH = 4  # numbers of one progression read at the hints alone that end the quick pass
POLAR_DETECT_SCALE = 0.75  # of the strip's size for its text detection: the same 130 of 300 dev renders and 7 of 21
# real photos refused as at full size, for about half its cost (57 -> ~30 ms on an 875 px strip)
TURNED_GLYPHS = 0.25  # share of the hints' readings that are glyphs of turned numbers above which the dial is
# taken to print its numbers turned and read by the full pass (a lone glyph, left out, sent 4 of 5 renders there)
OUTER_SCALE = 1.12  # scale radii: two numbers beyond this that the hints missed send the quick pass on


class DialTextReader:
    """Reads the texts of a rectified dial image with the PP-OCR engine; :class:`gauged.reader.stages.ocr.ScaleTextReader`
    builds the OCR stage on it.

    ``threads`` is onnxruntime's intra-op thread count, ``models`` the wheel whose ONNX files are
    used (:data:`gauged.reader.ocr.engine.MODEL_SETS`), ``min_score`` the recogniser score under
    which a reading is tried in other orientations and, if still under, dropped. ``det_side`` is the
    detector's input side in pixels for the ring around the circle. ``int8_detector`` is the int8
    copy of the text detector to run instead of the float one (:class:`OcrEngine`); ``number_net`` the
    number net's ONNX file (:mod:`gauged.reader.ocr.number_net`) that reads digit lines again, and
    ``minus_net`` the minus net's (:mod:`gauged.reader.ocr.minus_net`) that tells the minus signs the
    text boxes left out.
    """

    def __init__(self, threads: int = 2, models: str = DEFAULT_MODEL_PACKAGE, min_score: float = 0.5,
                 det_side: int = 384, use_hints: bool = True, progression: bool = True,
                 polar_fallback: bool = True, quick: bool = True, int8_detector: Path | None = None,
                 number_net: Path | None = None, minus_net: Path | None = None) -> None:
        self.engine = OcrEngine(threads=threads, package=models, int8_detector=int8_detector,
                                number_net=NumberNet(number_net, threads) if number_net is not None else None)
        self.minus_net = MinusNet(minus_net, threads) if minus_net is not None else None
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

    def read_at_hints(self, image_bgr: np.ndarray, hints: np.ndarray, circle: Circle) -> tuple[list[TextBox], int]:
        """The quick pass: the ink blob at each hint (predicted number centre, px) recognised, all in
        one batch, no text detection. Returns the readings that parse as numbers, less the single
        glyphs of turned numbers (read alone, the "4" of a "40" is a number too), and how many such
        glyphs were left out."""
        in_ring = [(hx, hy) for hx, hy in np.asarray(hints, float).reshape(-1, 2) if _in_ring((hx, hy), circle)]
        inks = _inks(image_bgr, in_ring, circle[2])
        parts = [quad for quad, turned_part in inks if turned_part]
        boxes = [b for b in self._recognise(image_bgr, [quad for quad, _ in inks], circle) if parse_number(b.text)]
        glyph = [any(np.array_equal(b.quad, quad) for quad in parts) for b in boxes]
        numbers = _split_spaced(_dedupe([b for b, g in zip(boxes, glyph, strict=True) if not g]))
        return numbers, sum(glyph)

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
        around the degC one it did), which only the full pass reads. Glyphs of turned numbers read
        alone (:meth:`read_at_hints`) are left out, and more than :data:`TURNED_GLYPHS` of them
        send the dial to the full pass.
        """
        if not self.quick or hints is None or len(hints) < QUICK_ENOUGH:
            return None, []
        numbers, glyphs = self.read_at_hints(image_bgr, hints, circle)
        if glyphs > TURNED_GLYPHS * (len(numbers) + glyphs):
            # A dial printing its numbers turned: glyphs of a turned "30, 40, 50" read "3, 4, 5" agree on
            # a line ten times too flat (a synthetic render, 86% off); the full pass reads the detector's
            # turned boxes whole.
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
