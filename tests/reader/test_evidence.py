"""The evidence terms of a reading and the calibrated confidence they give, on dials of known truth."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from gauged.reader.evidence import LOOKS, Calibration, evidence
from gauged.reader.gauge_read import GaugeRead, KnownScale
from gauged.reader.pipeline import GaugeReader
from gauged.types import ScaleMarker

from .dial_maps import CROP, Dial
from .test_failure_reasons import DialCropModel

IMAGE = np.full((CROP, CROP, 3), 200, np.uint8)
BOX = (0.0, 0.0, float(CROP), float(CROP))


def _known_read(reader: GaugeReader) -> GaugeRead:
    read = reader.read_box(IMAGE, BOX, known=KnownScale(0.0, 10.0, "bar"))
    assert read.failure is None and read.value is not None
    return read


def test_a_read_with_a_configured_scale_names_its_look_and_parts():
    dial = Dial()
    read = _known_read(GaugeReader(DialCropModel(dial), ocr=None))
    terms = evidence(read)

    assert terms["look_known"] == 1.0 and sum(terms[f"look_{look}"] for look in LOOKS) == 1.0
    assert terms["trust"] == read.value.trust == read.value.confidence  # no calibration: confidence is the trust
    assert terms["needle_mask"] == read.needle.mask_score and terms["notches"] == len(read.arc.notches)
    assert abs(terms["arc_span"] - dial.span_deg / 360) < 0.02
    assert terms["numbers"] == 0.0 and terms["falling"] == 0.0  # a prior prints no numbers; 0..10 rises
    assert abs(terms["edge"] - min(read.value.position, 1 - read.value.position)) < 1e-9
    # the drawn needle reaches 0.85 radii from the centre (the mask is sampled at stride 2)
    assert abs(terms["needle_reach"] - 0.85) < 0.05


def test_a_refused_read_has_no_evidence():
    assert evidence(GaugeRead(box=BOX, score=1.0)) == {}


def test_the_calibration_is_the_logistic_of_its_standardised_terms(tmp_path):
    calibration = Calibration(("needle_mask", "look_known"), np.array([0.5, 0.0]), np.array([0.25, 1.0]),
                              np.array([2.0, -1.0]), 0.3)
    path = tmp_path / "confidence.json"
    path.write_text(__import__("json").dumps(calibration.to_dict()))
    loaded = Calibration.load(path)

    terms = {"needle_mask": 0.9, "look_known": 1.0, "not_a_term": 5.0}
    z = 2.0 * (0.9 - 0.5) / 0.25 - 1.0 * 1.0 + 0.3
    assert math.isclose(loaded.probability(terms), 1 / (1 + math.exp(-z)))
    assert Calibration.load(tmp_path / "missing.json") is None


def test_the_calibration_gives_a_scale_read_by_ocr_its_probability_and_keeps_the_trust():
    dial = Dial()
    plain = _known_read(GaugeReader(DialCropModel(dial), ocr=None))
    calibration = Calibration(("needle_mask",), np.array([0.0]), np.array([1.0]), np.array([0.0]), -1.0)
    as_read_by_ocr = calibration.apply(replace(plain, look="first", value=plain.value))
    assert math.isclose(as_read_by_ocr.value.confidence, 1 / (1 + math.e))  # sigmoid(-1): the bias alone
    assert as_read_by_ocr.value.trust == plain.value.trust and as_read_by_ocr.value.value == plain.value.value


def test_configured_and_locked_scales_keep_the_trust_as_confidence():
    """The calibration is fitted on scales read by OCR; the tracker weighs readings by confidence,
    so a configured or locked scale's reading keeps the trust it always had."""
    calibration = Calibration(("needle_mask",), np.array([0.0]), np.array([1.0]), np.array([0.0]), -1.0)
    reader = GaugeReader(DialCropModel(Dial()), ocr=None, calibration=calibration)
    known = _known_read(reader)
    assert known.look == "known" and known.value.confidence == known.value.trust
    locked = reader.read_locked(IMAGE, BOX, known.arc, known.scale)
    assert locked.look == "locked" and locked.value.confidence == locked.value.trust


def test_the_shipped_calibration_loads_and_knows_its_terms():
    calibration = Calibration.load()
    assert calibration is not None, "gauged/models/confidence.json is shipped"
    assert set(calibration.terms) <= set(evidence(_known_read(GaugeReader(DialCropModel(Dial()), ocr=None))))


def test_net_minus_against_counts_the_agreeing_positive_numbers_the_number_net_saw_a_minus_before():
    read = _known_read(GaugeReader(DialCropModel(Dial()), ocr=None))
    box = (0.0, 0.0, 10.0, 10.0)
    markers = (ScaleMarker("2", 2.0, box, 0.1, True, net_minus=True),
               ScaleMarker("4", 4.0, box, 0.2, True, net_minus=True),
               ScaleMarker("6", 6.0, box, 0.3, True),  # no minus seen
               ScaleMarker("-8", -8.0, box, 0.4, True, net_minus=True),  # a negative number: the minus agrees
               ScaleMarker("5", 5.0, box, 0.5, False, net_minus=True))  # left out of the line
    read.scales = [replace(read.scales[0], markers=markers)]
    assert evidence(read)["net_minus_against"] == 2.0
