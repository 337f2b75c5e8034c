"""The number net at run time, and the reader's retry with it after a scale refusal."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from gauged.config.model import ReaderConfig
from gauged.reader.factory import NUMBER_NET_MODEL, build_reader
from gauged.reader.ocr.number_net import CHARS, NumberNet, greedy_decode, to_line_input
from gauged.reader.ocr.text import crop_quad
from gauged.reader.onnx_model import packaged_model_path
from gauged.reader.stages.scale import across_zero
from gauged.synth.crop import render_crop
from gauged.synth.dataset import render_item
from gauged.types import Ellipse, ScaleModel

pytestmark = pytest.mark.skipif(not packaged_model_path(NUMBER_NET_MODEL).is_file(),
                                reason=f"gauged/models/{NUMBER_NET_MODEL} is missing: see docs/ocr.md")


def _true_lines(seed: int, min_captured_px: float = 10.0):
    """Main-scale numbers of a render captured at least ``min_captured_px`` tall, cut at their true
    quads the way the net was trained."""
    sample = render_crop(seed, 448, masks=False)
    out = []
    for number in sample.truth["scales"][0]["numbers"]:
        quad = np.asarray(number["quad"], float)
        h, w = np.linalg.norm(quad[0] - quad[3]), max(1.0, np.linalg.norm(quad[0] - quad[1]))
        if h / sample.output_scale < min_captured_px:
            continue
        grown = quad.mean(axis=0) + (quad - quad.mean(axis=0)) * np.array([1.0 + 0.5 * h / w, 1.5])
        out.append((crop_quad(sample.image, grown), number["text"].replace("\u2212", "-")))
    return out


def test_the_net_reads_rendered_scale_numbers():
    net = NumberNet(packaged_model_path(NUMBER_NET_MODEL), threads=1)
    lines = [line for seed in range(2_200_000, 2_200_020) for line in _true_lines(seed)]  # seeds it never saw
    read = net.read([image for image, _ in lines])
    right = np.mean([r == text for r, (_, text) in zip(read, lines)])
    assert len(lines) > 40 and right >= 0.85  # ~94% of numbers captured 10 px or more (docs/ocr.md)
    assert net.read([]) == []


def test_line_input_and_best_path():
    x = to_line_input(np.full((10, 30, 3), 200, np.uint8))
    assert x.shape == (32, 128) and x.dtype == np.uint8 and (x == 200).all()
    logits = np.full((1, 5, len(CHARS) + 1), -5.0)
    for t, k in enumerate([3, 3, 0, 3, 12]):  # "2", "2" (merged), blank, "2", ","
        logits[0, t, k] = 5.0
    assert greedy_decode(logits) == ["22,"]


def test_a_retried_scale_across_zero_is_not_trusted():
    def scale(lo, hi):
        return ScaleModel(Ellipse(0, 0, 1, 1, 0), 1.0, 0.0, 0.0, lo, hi, None, 3, 0.0, ())

    assert across_zero(scale(-0.6, 0.4))  # "-0.5", "-0.2" read without their minus signs
    assert not across_zero(scale(-0.28, 300.0))  # a fitted 0 end lands a little off zero
    assert not across_zero(scale(-1.0, 0.02)) and not across_zero(scale(-30.0, 0.0))


def _held_out(index: int) -> tuple[np.ndarray, dict]:
    """Held-out render ``index`` (seed 9,000,000) as `gauged synth images` writes it (JPEG)."""
    image, record, _ = render_item(("crop", 9_000_000, index, 0, 0, 448, False))
    ok, jpeg = cv2.imencode(".jpg", image, [cv2.IMWRITE_JPEG_QUALITY, 95])
    return cv2.imdecode(jpeg, cv2.IMREAD_COLOR), record["gauges"][0]


def test_a_dial_refused_by_ppocr_numbers_is_read_by_the_number_net():
    # Two held-out dials whose PP-OCR numbers leave two agreeing (render 80, used before, sits on the
    # edge of the secondary-scale check and flips with the thread count and any OCR change).
    reader = build_reader(ReaderConfig(threads=1))
    without_net = build_reader(ReaderConfig(threads=1, ocr_number_net=False))
    for index in (280, 422):
        image, truth = _held_out(index)
        with_net, without = reader.read_image(image)[0], without_net.read_image(image)[0]
        assert without.failure is not None and without.failure.stage == "scale", index
        assert with_net.failure is None and with_net.look == "number_net", index
        assert abs(with_net.value.value - truth["value"]) <= 0.01 * (truth["max"] - truth["min"]), index


def test_the_engine_takes_the_nets_numbers_only_inside_its_block():
    from gauged.reader.ocr.engine import OcrEngine
    from gauged.reader.ocr.numbers import parse_number
    from gauged.types import StageFailure

    net = NumberNet(packaged_model_path(NUMBER_NET_MODEL), threads=1)
    engine, plain = OcrEngine(threads=1, number_net=net), OcrEngine(threads=1)
    lines = [image for seed in (2_200_000, 2_200_001) for image, _ in _true_lines(seed, 0.0)]
    with engine.reading_numbers_again():
        assert engine.numbers_again
        inside = engine.recognize(lines)
    assert not engine.numbers_again
    outside = engine.recognize(lines)  # the memo holds PP-OCR's readings only
    assert [r.digits for r in outside] == [r.digits for r in plain.recognize(lines)]
    for pp, again, by_net in zip(outside, inside, net.read(lines)):
        takes = bool(pp.digits) and bool(by_net) and not isinstance(parse_number(by_net), StageFailure)
        assert again.digits == (by_net if takes else pp.digits)
        assert again.score == pp.score  # the scores stay PP-OCR's
    with pytest.raises(RuntimeError, match="no number net"):
        with plain.reading_numbers_again():
            pass
