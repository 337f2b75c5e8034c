"""The minus net on lines drawn with a known sign, alone and in the minus look."""

from __future__ import annotations

import numpy as np
import pytest

from gauged.reader.ocr.minus_net import INPUT_WIDTH, minus_input
from gauged.reader.ocr.minus_sign import LEFT_MARGIN, SIGN_ODDS, left_extended, summed_minus_signs, with_seen_minus
from gauged.reader.ocr.text import TextBox, crop_quad

from tests.reader.ocr.test_minus_sign import _faint_minus_line, _ring_below, number_net  # noqa: F401 (a fixture)


@pytest.fixture(scope="module")
def minus_net():
    from gauged.reader.factory import MINUS_NET_MODEL
    from gauged.reader.ocr.minus_net import MinusNet
    from gauged.reader.onnx_model import packaged_model_path

    path = packaged_model_path(MINUS_NET_MODEL)
    if not path.is_file():
        pytest.skip(f"gauged/models/{MINUS_NET_MODEL} is missing: see docs/ocr.md")
    return MinusNet(path, threads=1)


def test_the_input_is_the_left_end_of_the_number_nets_line():
    line = np.full((20, 60, 3), 200, np.uint8)  # 32 x 96 once resized: its left 64 columns are kept
    line[:, :10] = 0  # 16 columns once resized
    x = minus_input(line)
    assert x.shape == (32, INPUT_WIDTH) and x.dtype == np.uint8
    assert x[:, :14].mean() < 60 and x[:, 18:].mean() > 180


def test_no_lines_give_no_odds(minus_net):
    assert minus_net.log_odds([]).shape == (0,)


def test_a_faint_minus_outside_the_box_is_told_from_digits_alone(minus_net):
    # (In this drawn font the net misses the minus before a "1", "2", "4", "6", "7" or "9" now and then:
    # their first strokes lean or curve unlike the engine's fonts; the number net's evidence must agree.)
    texts = ["-30", "-50", "-5", "-0.5", "40", "60", "25", "100"]
    image, quads = _faint_minus_line(texts)
    odds = minus_net.log_odds([crop_quad(image, left_extended(q, LEFT_MARGIN)) for q in quads])
    assert [bool(o > 0) for o in odds] == [t.startswith("-") for t in texts], odds


def _signed(boxes, image, number_net, minus_net):
    return with_seen_minus(boxes, image, circle=_ring_below(image), net_odds=number_net.minus_log_odds,
                           minus_odds=minus_net.log_odds)


@pytest.mark.parametrize("scale", [1.0, 1.2, 1.6])
def test_the_two_nets_evidence_signs_a_scale_of_negatives(minus_net, number_net, scale):
    texts = ["-50", "-30", "-5", "0"]
    image, quads = _faint_minus_line(texts, scale)
    boxes = [TextBox(t.lstrip("-"), 0.9, q) for t, q in zip(texts, quads)]
    assert [b.text for b in _signed(boxes, image, number_net, minus_net)] == texts


def test_minus_signs_on_a_few_numbers_of_a_dial_do_not_sign_it(minus_net, number_net):
    # Three numbers with a minus among seven: the four without outweigh them (a tick or a blur beside a
    # number is read as its minus by both nets now and then).
    texts = ["-50", "-30", "40", "60", "80", "100"]
    image, quads = _faint_minus_line(texts)
    boxes = [TextBox(t.lstrip("-"), 0.9, q) for t, q in zip(texts, quads)]
    out = _signed(boxes, image, number_net, minus_net)
    assert [b.text for b in out] == [t.lstrip("-") for t in texts]
    # the signs seen stay on the boxes as evidence against a reading that leaves those numbers positive
    assert [b.net_minus for b in out] == [True, True, False, False, False, False]


def test_a_dial_is_signed_by_the_sum_of_its_lines_evidence_not_by_one_sure_line():
    # Made-up nets: one line both are sure of (clipped), three that lean slightly against; then every
    # line leaning to a minus in both nets; then the nets disagreeing on every line.
    texts = ["30", "10", "5", "20"]
    image, quads = _faint_minus_line(texts)
    boxes = [TextBox(t, 0.9, q) for t, q in zip(texts, quads)]
    ring = _ring_below(image)
    sure_one = np.array([50.0, -0.5, -0.5, -0.5])
    signed, leaning = summed_minus_signs(boxes, image, lambda lines, digits: sure_one, lambda lines: sure_one, ring)
    assert signed == set() and leaning == {0}
    signed, leaning = summed_minus_signs(boxes, image, lambda lines, digits: np.full(len(lines), 0.8),
                                         lambda lines: np.full(len(lines), 2.0), ring)
    assert 4 * 0.8 > SIGN_ODDS and signed == leaning == {0, 1, 2, 3}
    signed, leaning = summed_minus_signs(boxes, image, lambda lines, digits: np.array([9.0, 9.0, -1.0, -1.0]),
                                         lambda lines: np.array([-1.0, -1.0, 9.0, 9.0]), ring)
    assert signed == leaning == set()
