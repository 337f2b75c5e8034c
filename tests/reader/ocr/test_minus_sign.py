"""Minus signs found in a text line's pixels, on lines drawn with known text."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from gauged.reader.ocr.minus_sign import shows_minus, with_seen_minus
from gauged.reader.ocr.text import TextBox


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
