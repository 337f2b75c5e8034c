"""The reading pipeline: the stages in order, for one gauge box or for every gauge in an image.

    detect -> crop -> keypoints (crop model) -> ellipse (scale arc) -> needle -> ocr -> scale -> reading

Each stage is a function in its own module returning a result or a :class:`StageFailure`; this module
only runs them in order, stops at the first failure, and keeps every intermediate result so a debug
picture or a scale lock can use them. A known scale (configured prior or a locked scale) skips OCR.
"""

from __future__ import annotations

import threading

import numpy as np

from gauged.reader.evidence import Calibration
from gauged.reader.failures import OCR_UNAVAILABLE
from gauged.reader.gauge_read import (
    GaugeRead,
    KnownScale,
    MarkersRead,
    ScaleTextReader,
    _progress,
    _Timer,
)
from gauged.reader.locate import locate_gauges, whole_image, wider_boxes
from gauged.reader.looks import EndsLooks
from gauged.reader.ocr.hint_numbers import MIN_NUMBERS as MIN_HINT_NUMBERS
from gauged.reader.ocr.units import PrintedUnit
from gauged.reader.onnx_model import OnnxModel, to_model_input
from gauged.reader.stages.crop import Crop, crop_gauge
from gauged.reader.stages.detect import GaugeDetector
from gauged.reader.stages.ellipse import (
    NO_SCALE_ENDS,
    NUMBERS_OUTSIDE_SCALE,
    POOR_FIT,
    ScaleArc,
    fit_scale_arc,
)
from gauged.reader.stages.keypoints import (
    CropKeypoints,
    decode_crop_maps,
    sure_numbers,
)
from gauged.reader.stages.needle import NeedleReading, fit_needle
from gauged.reader.stages.needle_scan import NeedleLook, scan_needle
from gauged.reader.stages.notch_check import NotchCheck
from gauged.reader.stages.ocr import NO_NUMBERS
from gauged.reader.stages.reading import read_value
from gauged.reader.stages.scale import (
    across_zero,
    fit_scales,
    primary_first,
    scale_from_prior,
)
from gauged.types import Box, ScaleModel, StageFailure

DETAIL_SIZE = 640  # px: the largest square the OCR samples its rectified view from
DETAIL_GAIN = 1.25  # use the frame's pixels for OCR when they hold this much more detail than the crop
SECOND_LOOK = ("ocr", "scale")  # refusals of these stages (ocr: only no_numbers) get ScaleTextReader.reread_markers


class GaugeReader(EndsLooks):
    """Reads gauges with the shipped models. Create once; ``read_image`` / ``read_box`` per frame."""

    def __init__(self, crop_model: OnnxModel, detector: GaugeDetector | None = None,
                 ocr: ScaleTextReader | None = None, min_confidence: float = 0.5, crop_pad: float = 0.08,
                 notch_check: NotchCheck | None = None, calibration: Calibration | None = None):
        self.crop_model = crop_model
        self.calibration = calibration  # None: a reading's confidence is its trust
        self.notch_check = notch_check
        self.detector = detector
        self.ocr = ocr
        self.min_confidence = min_confidence
        self.crop_pad = crop_pad
        # Full reads run one at a time (locked reads do not wait): each already uses every core it
        # is given, and four cameras' cold reads at once held the OCR's working memory four times
        # (the daemon's peak RSS under bench/bench_load.py: see docs/performance.md).
        self._full_reads = threading.Lock()

    @property
    def crop_size(self) -> int:
        return self.crop_model.input_size

    def read_image(self, image: np.ndarray, known: KnownScale | None = None,
                   primary_unit: str | None = None) -> list[GaugeRead] | StageFailure:
        """Locate every gauge in (H, W, 3) uint8 BGR ``image`` (:func:`gauged.reader.locate.locate_gauges`,
        the daemon's rules) and read each box as the daemon reads a located gauge, best first.

        When the detector found nothing and the image read whole shows no scale arc either, the
        detector's failure is returned.
        """
        located, failure = locate_gauges(self.detector, image)
        reads = [self.read_box(image, d.box, d.score, known, primary_unit, located=True) for d in located]
        if failure is not None and reads[0].failure is not None and reads[0].arc is None:
            return failure
        return reads

    def read_box(self, image: np.ndarray, box: Box, score: float = 1.0, known: KnownScale | None = None,
                 primary_unit: str | None = None, located: bool = False) -> GaugeRead:
        """Read the gauge inside ``box`` (frame pixels) of (H, W, 3) uint8 BGR ``image``.

        A configured ROI is read as given. A ``located`` box (:mod:`gauged.reader.locate`) that holds
        no scale ring is read again in larger boxes (:func:`gauged.reader.locate.wider_boxes`): the detector sometimes
        boxes only the hub, the upper face or a printed number of a dial that fills the view, and a
        photo cut to its dial runs past the dial's notches. The first wider read that finds a ring is
        kept, else the read that got furthest. A ring refused for its notch fit gets the notch check's
        last look (:meth:`_ring_of_checked_notches`). A dial found and then refused (needle, OCR,
        scale) is not read again: every try is another chance for a wrong scale to pass a check.
        Full reads of several threads run one at a time.
        """
        with self._full_reads:
            return self._read_box(image, box, score, known, primary_unit, located)

    def _read_box(self, image: np.ndarray, box: Box, score: float, known: KnownScale | None,
                  primary_unit: str | None, located: bool) -> GaugeRead:
        read = self._read_once(image, box, score, known, primary_unit)
        # (an image read whole that shows no notch at all is no dial, not a dial cut by the image's edges)
        stages = ("ellipse",) if tuple(box) == whole_image(image) else ("crop", "keypoints", "ellipse")
        if located and read.arc is None and read.failure is not None and read.failure.stage in stages:
            for wider in wider_boxes(image, box):
                again = self._read_once(image, wider, score, known, primary_unit)
                if again.arc is not None:
                    read = again
                    break
                read = again if _progress(again) > _progress(read) else read
        return self._calibrated(self._ring_of_checked_notches(image, read, known, primary_unit))

    def _calibrated(self, read: GaugeRead) -> GaugeRead:
        return read if self.calibration is None else self.calibration.apply(read)

    def _ring_of_checked_notches(self, image: np.ndarray, read: GaugeRead, known: KnownScale | None,
                                 primary_unit: str | None) -> GaugeRead:
        """A read refused because its notch peaks fit no ring (``poor_fit``, after the reader's other
        looks), read once more in the same box on the major peaks the notch check keeps; the read that
        got further is kept.

        The crop model's major peaks include minor ticks, which bend the ring through them; the notch
        check drops most of them (gauged/models/README.md). It is the last look, and only at rings
        refused: kept on every crop, it changed right readings too, some of them to wild ones.
        """
        if (self.notch_check is None or read.failure is None or read.failure.stage != "ellipse"
                or read.failure.reason != POOR_FIT):
            return read
        again = self._read_once(image, read.box, read.score, known, primary_unit, check_notches=True)
        again.checked_notches = True
        return again if _progress(again) > _progress(read) else read

    def _read_once(self, image: np.ndarray, box: Box, score: float = 1.0, known: KnownScale | None = None,
                   primary_unit: str | None = None, check_notches: bool = False) -> GaugeRead:
        """One read of the gauge inside ``box``; with ``check_notches`` (only when the reader has a
        notch check), on the major peaks the notch check keeps."""
        result = GaugeRead(box=box, score=score)
        timer = _Timer(result.seconds)
        if not self._crop_and_keypoints(image, box, result, timer, require_notches=True, check_notches=check_notches):
            return result
        crop, keypoints = result.crop, result.keypoints
        with timer("ellipse"):
            arc = fit_scale_arc(keypoints, self.crop_size)
        if isinstance(arc, StageFailure):
            result.failure = arc
            # ends refuted by numbers in their gap, or (with the scale configured) not found at all
            if self.ocr is not None and (arc.reason == NUMBERS_OUTSIDE_SCALE
                                         or (known is not None and arc.reason == NO_SCALE_ENDS)):
                self._between_numbers(image, crop, keypoints, result, timer, known)
            return result
        result.arc = arc
        with timer("needle"):
            needle = fit_needle(keypoints.needle_prob, keypoints.stride, arc)
        if isinstance(needle, StageFailure):
            result.failure = needle
            return result
        result.needle = needle
        scales = self._scales(image, crop, keypoints, arc, known, primary_unit, result, timer)
        if isinstance(scales, StageFailure) and scales.stage == "scale":
            pivoted = self._about_pivot(image, crop, keypoints, arc, result, timer)
            if pivoted is not None:
                arc, needle, scales = pivoted
                result.arc, result.needle, result.look = arc, needle, "pivot"
                primary_first(scales, primary_unit)
        if isinstance(scales, StageFailure):
            result.failure = scales
            return result
        result.scales = scales
        with timer("reading"):
            value = read_value(needle, arc, scales[0], self.min_confidence)
        if isinstance(value, StageFailure):
            result.failure = value
            return result
        result.value = value
        return result

    def read_locked(self, image: np.ndarray, box: Box, arc: ScaleArc, scale: ScaleModel,
                    look: NeedleLook | None = None) -> GaugeRead:
        """Read only the needle against a locked scale arc and map (crop pixels of a crop of ``box``).

        The cheap steady-state path of a fixed camera: crop, crop model, needle, value — no ellipse
        fit, no OCR. ``keypoints.pivot`` is kept so the caller can check the dial has not moved.
        With the needle's ``look`` (:func:`gauged.reader.stages.needle_scan.learn_needle_look`), the
        needle is first found by a radial scan instead, without the crop model; a read so made has no
        ``keypoints``. A frame the scan cannot tell is read with the crop model as before.
        """
        result = GaugeRead(box=box, score=1.0, arc=arc, scales=[scale], look="locked")
        timer = _Timer(result.seconds)
        crop = None
        if look is not None:
            with timer("crop"):
                crop = crop_gauge(image, box, self.crop_size, self.crop_pad)
            if not isinstance(crop, StageFailure):
                with timer("needle_scan"):
                    scanned = scan_needle(crop.image, arc, look)
                if not isinstance(scanned, StageFailure):
                    result.crop = crop
                    return self._locked_value(result, scanned, arc, scale, timer)
        if not self._crop_and_keypoints(image, box, result, timer, require_notches=False, crop=crop):
            return result
        keypoints = result.keypoints
        with timer("needle"):
            needle = fit_needle(keypoints.needle_prob, keypoints.stride, arc)
        if isinstance(needle, StageFailure):
            result.failure = needle
            return result
        return self._locked_value(result, needle, arc, scale, timer)

    def _locked_value(self, result: GaugeRead, needle: NeedleReading, arc: ScaleArc, scale: ScaleModel,
                      timer: _Timer) -> GaugeRead:
        result.needle = needle
        with timer("reading"):
            value = read_value(needle, arc, scale, self.min_confidence)
        if isinstance(value, StageFailure):
            result.failure = value
        else:
            result.value = value
        return self._calibrated(result)

    def _read_on(self, image: np.ndarray, crop: Crop, keypoints: CropKeypoints, arc: ScaleArc, timer: _Timer,
                 min_inliers: int = 3) -> tuple[MarkersRead, list[ScaleModel]] | None:
        """The markers and units read on the dial rectified by ``arc`` and the scales they give (at least
        ``min_inliers`` agreeing numbers), or None when the OCR or the scale stage refuses."""
        with timer("ocr"):
            read = self.ocr.read_markers(crop.image, arc, keypoints.numbers.points, self._detail(image, crop))
        if isinstance(read, StageFailure):
            return None
        with timer("scale"):
            scales = fit_scales(arc, read[0], read[1], min_inliers=min_inliers, hints=sure_numbers(keypoints.numbers))
        return None if isinstance(scales, StageFailure) else (read, scales)

    def _number_net_retry(self, crop: Crop, arc: ScaleArc, number_points: np.ndarray, detail: np.ndarray | None,
                          hints: np.ndarray, timer: _Timer
                          ) -> tuple[MarkersRead, list[ScaleModel]] | None:
        """The markers, units and scales of the dial read again with the number net, which misreads
        half as many small numbers as PP-OCR (docs/ocr.md), or None. Only a refused scale gets this
        read, and the refusal stands unless the scale stage accepts what it reads and the scale does
        not cross zero: the net drops minus signs."""
        with timer("ocr"):
            again = self.ocr.read_markers_by_number_net(crop.image, arc, number_points, detail)
        if isinstance(again, StageFailure):
            return None
        with timer("scale"):
            scales = fit_scales(arc, again[0], again[1], hints=hints)
        if isinstance(scales, StageFailure) or across_zero(scales[0]):
            return None
        return again, scales

    def _hint_look(self, image: np.ndarray, crop: Crop, keypoints: CropKeypoints, arc: ScaleArc,
                   units: tuple[PrintedUnit, ...],
                   hints: np.ndarray, result: GaugeRead, timer: _Timer) -> list[ScaleModel] | None:
        """The scales of the numbers the number net reads at the crop model's number peaks
        (:mod:`gauged.reader.ocr.hint_numbers`), or None: a last look at a dial whose text the OCR could
        not read. The refusal stands unless the scale stage accepts these numbers, and their scale
        does not cross zero (the net drops minus signs)."""
        if not self.ocr.has_number_net:
            return None
        with timer("ocr"):
            markers = self.ocr.hint_markers(image, crop, arc, keypoints.numbers)
        if not markers:
            return None
        with timer("scale"):
            scales = fit_scales(arc, markers, units, min_inliers=MIN_HINT_NUMBERS, hints=hints)
        if isinstance(scales, StageFailure) or across_zero(scales[0]):
            return None
        result.markers, result.units, result.look = markers, units, "hint"
        return scales

    def _detail(self, image: np.ndarray, crop: Crop) -> np.ndarray | None:
        """The crop's square region at up to :data:`DETAIL_SIZE` px when the frame has that much more
        detail than the model's crop: scale numbers are small, and OCR reads them far better from the
        frame's own pixels than from the crop the model needed (often 2-4x smaller)."""
        side = crop.box[2] - crop.box[0]
        size = int(min(DETAIL_SIZE, side))
        if size < DETAIL_GAIN * self.crop_size:
            return None
        detail = crop_gauge(image, crop.box, size, pad=0.0)
        return None if isinstance(detail, StageFailure) else detail.image

    def _crop_and_keypoints(self, image: np.ndarray, box: Box, result: GaugeRead, timer: _Timer,
                            require_notches: bool, check_notches: bool = False,
                            crop: Crop | StageFailure | None = None) -> bool:
        """Crop (unless ``crop`` is that of ``box`` already) and run the crop model into ``result``; False
        (with ``result.failure`` set) on failure."""
        if crop is None:
            with timer("crop"):
                crop = crop_gauge(image, box, self.crop_size, self.crop_pad)
        if isinstance(crop, StageFailure):
            result.failure = crop
            return False
        result.crop = crop
        with timer("keypoints"):
            model_input = to_model_input(crop.image)
            logits = self.crop_model(model_input)
            keypoints = decode_crop_maps(logits, self.crop_size, require_notches=require_notches)
            if check_notches and not isinstance(keypoints, StageFailure):
                keypoints = self.notch_check(model_input, logits, keypoints)
        if isinstance(keypoints, StageFailure):
            result.failure = keypoints
            return False
        result.keypoints = keypoints
        return True

    def _scales(self, image: np.ndarray, crop: Crop, keypoints: CropKeypoints, arc: ScaleArc, known: KnownScale | None,
                primary_unit: str | None, result: GaugeRead, timer: _Timer) -> list[ScaleModel] | StageFailure:
        if known is not None:
            result.look = "known"
            return [scale_from_prior(arc, known.min_value, known.max_value, known.unit, known.direction)]
        if self.ocr is None:
            return StageFailure("ocr", OCR_UNAVAILABLE, "no OCR engine and no configured scale")
        detail = self._detail(image, crop)
        numbers = keypoints.numbers
        hints = sure_numbers(numbers)
        with timer("ocr"):
            read = self.ocr.read_markers(crop.image, arc, numbers.points, detail)
        if isinstance(read, StageFailure):
            if read.reason != NO_NUMBERS:
                return self._hint_look(image, crop, keypoints, arc, (), hints, result, timer) or read
            units, scales = (), read  # texts but no number: the second look below may find some
        else:
            result.markers, units = read
            with timer("scale"):
                scales = fit_scales(arc, result.markers, units, hints=hints)
            if isinstance(scales, StageFailure) and scales.stage == "scale" and self.ocr.has_number_net:
                retried = self._number_net_retry(crop, arc, numbers.points, detail, hints, timer)
                if retried is not None:
                    (result.markers, units), scales = retried
                    result.look = "number_net"
        result.units = units
        if isinstance(scales, StageFailure) and scales.stage in SECOND_LOOK:
            # The numbers read gave no scale: look again for the grid the ring's texts most likely
            # print (gauged.reader.ocr.likely_scale). Only refusals get this look, and the original
            # refusal stands unless the scale stage accepts what it finds.
            with timer("ocr"):
                again = self.ocr.reread_markers(crop.image, arc, numbers.points, detail)
            if again:
                with timer("scale"):
                    retry = fit_scales(arc, again, units, hints=hints)
                if not isinstance(retry, StageFailure):
                    result.markers, scales, result.look = again, retry, "likely_scale"
        if isinstance(scales, StageFailure):
            scales = self._hint_look(image, crop, keypoints, arc, units, hints, result, timer) or scales
        if isinstance(scales, StageFailure):
            return scales
        primary_first(scales, primary_unit)
        return scales
