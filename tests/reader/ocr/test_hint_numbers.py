"""The last look: the number net reading windows at the crop model's number peaks."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from gauged.config.model import ReaderConfig
from gauged.reader.factory import NUMBER_NET_MODEL, build_reader
from gauged.reader.ocr.hint_numbers import (
    WELL_FORMED,
    _read_guess,
    hint_markers,
    window_quad,
)
from gauged.reader.ocr.number_net import NumberNet
from gauged.reader.onnx_model import packaged_model_path
from gauged.reader.stages.crop import Crop
from gauged.synth.dataset import render_item

needs_net = pytest.mark.skipif(not packaged_model_path(NUMBER_NET_MODEL).is_file(),
                               reason=f"gauged/models/{NUMBER_NET_MODEL} is missing: see docs/ocr.md")


def test_windows_are_centred_with_their_top_along_up():
    upright = window_quad(np.array([100.0, 50.0]), 10.0, 30.0, np.array([0.0, -1.0]))
    assert np.allclose(upright, [[85, 45], [115, 45], [115, 55], [85, 55]])  # top-left first, y down
    radial = window_quad(np.array([100.0, 50.0]), 10.0, 30.0, np.array([1.0, 0.0]))  # a number right of the centre
    assert np.allclose(radial.mean(axis=0), [100, 50])
    assert np.allclose(radial[0], [105, 35]) and np.allclose(radial[3], [95, 35])  # its top faces outward (+x)


def test_only_numbers_as_printed_count():
    for text in ("0", "0.0", "10", "-10", "0.5", "-0.25", "2,5", "120"):
        assert WELL_FORMED.fullmatch(text), text
    for text in ("-0", "-0.0", "0.", "1.", "05", "", "1.2.3", "--5"):
        assert not WELL_FORMED.fullmatch(text), text


def _crop() -> Crop:
    return Crop(np.zeros((256, 256, 3), np.uint8), np.eye(3), (0.0, 0.0, 256.0, 256.0))


def test_a_guess_keeps_one_rings_numbers_on_its_line():
    angles = np.radians([0.0, 30.0, 60.0, 90.0, 120.0, 45.0])
    radii = np.array([0.8, 0.8, 0.82, 0.79, 0.8, 0.5])  # the last one is an inner scale's
    quads = [window_quad(np.array([50.0 + 20 * k, 60.0]), 10.0, 30.0, np.array([0.0, -1.0])) for k in range(6)]
    guess = _read_guess(["0", "10", "20", "-0", "40", "15"], quads, angles, radii, _crop())
    # "-0" is no printed number; "15" lies on the line (45 degrees) but at the inner scale's radius
    assert [m.value for m in guess.markers] == [0.0, 10.0, 20.0, 40.0]
    assert guess.agreeing == 4 and guess.characters == 7
    assert guess.markers[1].box == pytest.approx((55.0, 55.0, 85.0, 65.0))  # the window, in crop pixels
    assert _read_guess(["0.", "1.", "7", "-0"], quads[:4], angles[:4], radii[:4], _crop()) is None


def _held_out(index: int) -> tuple[np.ndarray, dict]:
    """Held-out render ``index`` (seed 9,000,000) as `gauged synth images` writes it (JPEG)."""
    image, record, _ = render_item(("crop", 9_000_000, index, 0, 0, 448, False))
    ok, jpeg = cv2.imencode(".jpg", image, [cv2.IMWRITE_JPEG_QUALITY, 95])
    return cv2.imdecode(jpeg, cv2.IMREAD_COLOR), record["gauges"][0]


@needs_net
def test_a_dial_whose_text_the_ocr_cannot_read_is_read_at_its_number_peaks():
    # Held-out 000432: a blurred 0..300 dial. PP-OCR and the number net's retry read no scale from it.
    image, truth = _held_out(432)
    without = build_reader(ReaderConfig(threads=1, ocr_number_net=False)).read_image(image)[0]
    assert without.failure is not None and without.failure.stage in ("ocr", "scale")
    read = build_reader(ReaderConfig(threads=1)).read_image(image)[0]
    assert read.failure is None
    assert abs(read.value.value - truth["value"]) <= 0.01 * (truth["max"] - truth["min"])
    printed = {n["value"] for n in truth["scales"][0]["numbers"]}
    assert len(read.markers) >= 4 and {m.value for m in read.markers} <= printed
    # the look itself, on the same dial and arc: at least four of the printed numbers on one line
    markers = hint_markers(image, read.crop, read.arc, read.keypoints.numbers,
                           NumberNet(packaged_model_path(NUMBER_NET_MODEL), threads=1))
    assert markers is not None and len(markers) >= 4 and {m.value for m in markers} <= printed


def test_no_peaks_no_look():
    from gauged.reader.stages.keypoints import Peaks

    assert hint_markers(np.zeros((64, 64, 3), np.uint8), _crop(), None, Peaks(np.zeros((0, 2)), np.zeros(0)), None) is None


def test_a_guess_takes_numbers_falling_clockwise_too():
    """A 0..40 scale rising counter-clockwise, read without signs: its numbers fall clockwise, and the
    guess keeps all five on one line (the scale stage takes the direction from the signs)."""
    angles = np.radians([0.0, 30.0, 60.0, 90.0, 120.0])
    radii = np.full(5, 0.8)
    quads = [window_quad(np.array([50.0 + 20 * k, 60.0]), 10.0, 30.0, np.array([0.0, -1.0])) for k in range(5)]
    guess = _read_guess(["40", "30", "20", "10", "0"], quads, angles, radii, _crop())
    assert guess is not None and [m.value for m in guess.markers] == [40.0, 30.0, 20.0, 10.0, 0.0]
    rising = _read_guess(["0", "10", "20", "30", "7"], quads, angles, radii, _crop())
    assert [m.value for m in rising.markers] == [0.0, 10.0, 20.0, 30.0]  # the misread "7" left out


def test_a_minus_the_net_did_not_read_is_taken_from_the_window():
    from gauged.reader.ocr.hint_numbers import _with_seen_minus
    from gauged.types import ScaleMarker

    frame = np.full((60, 240, 3), 225, np.uint8)
    cv2.putText(frame, "-0.2", (10, 40), cv2.FONT_HERSHEY_SIMPLEX, 1.0, (30, 30, 30), 2, cv2.LINE_AA)
    cv2.putText(frame, "0.4", (140, 40), cv2.FONT_HERSHEY_SIMPLEX, 1.0, (30, 30, 30), 2, cv2.LINE_AA)
    signed = _with_seen_minus(ScaleMarker("0.2", 0.2, (0, 0, 1, 1)), frame, window_quad(np.array([60.0, 30.0]), 44.0, 110.0, np.array([0.0, -1.0])))
    assert (signed.text, signed.value) == ("-0.2", -0.2)
    plain = _with_seen_minus(ScaleMarker("0.4", 0.4, (0, 0, 1, 1)), frame, window_quad(np.array([180.0, 30.0]), 44.0, 100.0, np.array([0.0, -1.0])))
    assert (plain.text, plain.value) == ("0.4", 0.4)
