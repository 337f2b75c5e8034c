"""Minus signs found in a text line's pixels, on lines drawn with known text."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from gauged.reader.ocr.minus_sign import LEFT_MARGIN, faces_ticks, left_extended, shows_minus, with_seen_minus
from gauged.reader.ocr.text import TextBox, crop_quad


def _line(text: str, scale: float = 1.0, blur: int = 0, light_on_dark: bool = False, font=cv2.FONT_HERSHEY_SIMPLEX):
    """An upright line image holding ``text``, cut tight around the ink as the text detector does."""
    ink, face = ((235, 235, 235), (30, 30, 30)) if light_on_dark else ((20, 20, 20), (225, 230, 220))
    canvas = np.full((120, 400, 3), face, np.uint8)
    cv2.putText(canvas, text, (20, 80), font, scale, ink, max(1, int(round(2 * scale))), cv2.LINE_AA)
    if blur:
        canvas = cv2.GaussianBlur(canvas, (0, 0), blur)
    mask = np.abs(canvas.astype(int) - np.array(face)).sum(axis=2) > 60
    ys, xs = np.nonzero(mask)
    pad = max(2, int(4 * scale))
    return canvas[ys.min() - pad:ys.max() + pad, xs.min() - pad:xs.max() + pad]


@pytest.mark.parametrize("text", ["-40", "-100", "-0.5", "-1", "-25"])
@pytest.mark.parametrize("scale,blur,light", [(1.0, 0, False), (1.6, 0, True), (1.2, 1.5, False)])
def test_a_minus_before_the_digits_is_seen(text, scale, blur, light):
    assert shows_minus(_line(text, scale, blur, light))


@pytest.mark.parametrize("text", ["40", "100", "0.5", "1", "25", "7", "4", "2", "350", "17"])
@pytest.mark.parametrize("scale,blur,light", [(1.0, 0, False), (1.6, 0, True), (1.2, 1.5, False)])
def test_digits_alone_show_no_minus(text, scale, blur, light):
    assert not shows_minus(_line(text, scale, blur, light))


def test_tiny_or_blank_lines_show_no_minus():
    assert not shows_minus(np.full((5, 30, 3), 200, np.uint8))
    assert not shows_minus(np.full((30, 60, 3), 200, np.uint8))


def test_only_numbers_read_without_a_sign_get_one():
    image = np.full((200, 400, 3), 225, np.uint8)
    boxes = []
    for n, text in enumerate(["-40", "40", "-60", "bar"]):
        line = _line(text)
        x, y = 10 + 95 * n, 50
        image[y:y + line.shape[0], x:x + line.shape[1]] = line
        quad = np.float32([[x, y], [x + line.shape[1], y], [x + line.shape[1], y + line.shape[0]], [x, y + line.shape[0]]])
        boxes.append(TextBox(text.lstrip("-") if n == 0 else text, 0.9, quad))  # the first read without its minus
    assert [b.text for b in with_seen_minus(boxes, image)] == ["-40", "40", "-60", "bar"]


@pytest.fixture(scope="module")
def engine():
    from gauged.reader.ocr.engine import OcrEngine, OcrUnavailable

    try:
        return OcrEngine(threads=1)
    except OcrUnavailable as exc:
        pytest.skip(f"OCR models not installed: {exc}")


FACE = (225, 230, 220)


def _dial_line(texts: list[str], scale: float = 1.2) -> tuple[np.ndarray, list[np.ndarray]]:
    """An image holding ``texts`` side by side and, for each, the quad the text detector often gives
    it: from its first digit on, a minus left outside."""
    thick = max(1, int(2 * scale))
    image = np.full((120, 150 * len(texts), 3), FACE, np.uint8)
    quads = []
    for n, text in enumerate(texts):
        x = 30 + 150 * n
        cv2.putText(image, text, (x, 80), cv2.FONT_HERSHEY_SIMPLEX, scale, (20, 20, 20), thick, cv2.LINE_AA)
        ink = np.abs(image[:, x - 10:x + 140].astype(int) - FACE).sum(axis=2) > 60
        ys, xs = np.nonzero(ink)
        minus = cv2.getTextSize("-", cv2.FONT_HERSHEY_SIMPLEX, scale, thick)[0][0] if text.startswith("-") else 0
        x0, x1 = x + max(minus + 1, xs.min() - 10 - 3), x - 10 + xs.max() + 3
        y0, y1 = ys.min() - 3, ys.max() + 3
        quads.append(np.float32([[x0, y0], [x1, y0], [x1, y1], [x0, y1]]))
    return image, quads


@pytest.mark.parametrize("texts", [["-40", "-60"], ["-100", "-25", "-50"]])
def test_minus_signs_left_outside_the_boxes_are_read_on_the_widened_lines(engine, texts):
    image, quads = _dial_line(texts)
    lines = [crop_quad(image, q) for q in quads]
    read = [r.digits for r in engine.run_recogniser(lines)]
    assert read == [t[1:] for t in texts], f"the boxes should hold the digits only, read {read}"
    assert not any(shows_minus(line) for line in lines)
    boxes = [TextBox(t, 0.9, q) for t, q in zip(read, quads)]
    assert [b.text for b in with_seen_minus(boxes, image, engine.run_recogniser)] == texts
    assert [b.text for b in with_seen_minus(boxes, image)] == read  # the pixels alone miss them


def test_one_number_alone_with_a_minus_outside_its_box_keeps_its_reading(engine):
    # A tick beside one number reads as a minus as well: one such sign on a dial is not counted.
    image, quads = _dial_line(["-40", "60"])
    boxes = [TextBox(t, 0.9, q) for t, q in zip(["40", "60"], quads)]
    assert [b.text for b in with_seen_minus(boxes, image, engine.run_recogniser)] == ["40", "60"]


def test_numbers_with_nothing_before_them_get_no_minus_from_the_widened_lines(engine):
    image, quads = _dial_line(["40", "100", "25"])
    boxes = [TextBox(t, 0.9, q) for t, q in zip(["40", "100", "25"], quads)]
    assert [b.text for b in with_seen_minus(boxes, image, engine.run_recogniser)] == ["40", "100", "25"]


@pytest.fixture(scope="module")
def number_net():
    from gauged.reader.factory import NUMBER_NET_MODEL
    from gauged.reader.ocr.number_net import NumberNet
    from gauged.reader.onnx_model import packaged_model_path

    path = packaged_model_path(NUMBER_NET_MODEL)
    if not path.is_file():
        pytest.skip(f"gauged/models/{NUMBER_NET_MODEL} is missing: see docs/ocr.md")
    return NumberNet(path, threads=1)


def _faint_minus_line(texts: list[str], scale: float = 1.2) -> tuple[np.ndarray, list[np.ndarray]]:
    """``texts`` side by side, each minus fainter and thinner than its digits, blurred; for each, the
    quad the text detector often gives it: from its first digit on, the minus left outside."""
    thick = max(1, int(2 * scale))
    image = np.full((120, 150 * len(texts), 3), FACE, np.uint8)
    quads = []
    for n, text in enumerate(texts):
        x = 30 + 150 * n
        digits = text.lstrip("-")
        minus = cv2.getTextSize("-", cv2.FONT_HERSHEY_SIMPLEX, scale, thick)[0][0]
        if text.startswith("-"):
            cv2.putText(image, "-", (x, 80), cv2.FONT_HERSHEY_SIMPLEX, scale, (120, 120, 120), thick - 1, cv2.LINE_AA)
        cv2.putText(image, digits, (x + minus, 80), cv2.FONT_HERSHEY_SIMPLEX, scale, (20, 20, 20), thick, cv2.LINE_AA)
        (w, h), _ = cv2.getTextSize(digits, cv2.FONT_HERSHEY_SIMPLEX, scale, thick)
        x0, x1, y0, y1 = x + minus + 1, x + minus + w + 3, 80 - h - 3, 84
        quads.append(np.float32([[x0, y0], [x1, y0], [x1, y1], [x0, y1]]))
    return cv2.GaussianBlur(image, (0, 0), 1.0), quads


def _ring_below(image: np.ndarray) -> tuple[float, float, float]:
    """A scale ring (cx, cy, r) whose top, inside the ring, holds the line ``image``."""
    return (image.shape[1] / 2, 5060.0, 5100.0)


def test_the_number_nets_minus_signs_count_on_a_scale_of_negatives(number_net):
    texts = ["-30", "-10", "-5", "0"]
    image, quads = _faint_minus_line(texts)
    boxes = [TextBox(t.lstrip("-"), 0.9, q) for t, q in zip(texts, quads)]
    assert [b.text for b in with_seen_minus(boxes, image)] == ["30", "10", "5", "0"]  # the pixels alone miss them
    assert [b.text for b in with_seen_minus(boxes, image, net=number_net.read, circle=_ring_below(image))] == texts


def test_the_number_nets_minus_signs_on_a_few_numbers_of_a_dial_do_not_count(number_net):
    # The net reads a tick beside a number as its minus: signs on fewer than half the numbers are not a
    # scale of negatives. (The same three lines as above read "-" by the net, four positive numbers beside.)
    texts = ["-30", "-10", "-5", "40", "60", "80", "100"]
    image, quads = _faint_minus_line(texts)
    boxes = [TextBox(t.lstrip("-"), 0.9, q) for t, q in zip(texts, quads)]
    widened = [crop_quad(image, left_extended(q, LEFT_MARGIN)) for q in quads[:3]]
    assert number_net.read(widened) == texts[:3], "the net should read the three minus signs on their own"
    out = with_seen_minus(boxes, image, net=number_net.read, circle=_ring_below(image))
    assert [b.text for b in out] == [t.lstrip("-") for t in texts]
    # the signs seen stay on the boxes as evidence against a reading that leaves those numbers positive
    assert [b.net_minus for b in out] == [True, True, True, False, False, False, False]


def test_the_number_nets_minus_signs_before_numbers_that_face_the_ticks_do_not_count(number_net):
    # The same numbers at 9 o'clock inside their ring: their lines start toward the ring, whose ticks
    # run level with the digits there and read as minus signs.
    texts = ["-30", "-10", "-5", "0"]
    image, quads = _faint_minus_line(texts)
    boxes = [TextBox(t.lstrip("-"), 0.9, q) for t, q in zip(texts, quads)]
    at_nine = (image.shape[1] + 300.0, 60.0, image.shape[1] + 320.0)
    assert all(faces_ticks(q, at_nine) for q in quads) and not any(faces_ticks(q, _ring_below(image)) for q in quads)
    assert [b.text for b in with_seen_minus(boxes, image, net=number_net.read, circle=at_nine)] == ["30", "10", "5", "0"]


def test_numbers_that_face_the_ticks_count_among_the_numbers_but_never_among_the_signs(number_net):
    # A "40" at 9 o'clock on the ring's ticks beside two numbers the net reads with a minus (a tick or a
    # blur beside them): two signs of three numbers are not a scale of negatives, though both the net
    # reads count.
    texts = ["40", "-10", "-5"]
    image, quads = _faint_minus_line(texts)
    boxes = [TextBox(t.lstrip("-"), 0.9, q) for t, q in zip(texts, quads)]
    ring = (float(image.shape[1]), 360.0, 1000.0)
    assert [faces_ticks(q, ring) for q in quads] == [True, False, False]
    widened = [crop_quad(image, left_extended(q, LEFT_MARGIN)) for q in quads[1:]]
    assert number_net.read(widened) == texts[1:], "the net should read the two minus signs on their own"
    assert [b.text for b in with_seen_minus(boxes, image, net=number_net.read, circle=ring)] == ["40", "10", "5"]
