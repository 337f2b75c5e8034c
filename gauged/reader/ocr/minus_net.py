"""The minus net at run time: onnxruntime tells whether a minus stands before a number (no torch).

The minus look (:mod:`gauged.reader.ocr.minus_sign`) reads each unsigned number's line widened left
of its text box, where a faint minus PP-OCR decoded as nothing would stand. This small CNN, trained
by :mod:`gauged.training.minus_lines` on those lines as the reader cuts them from renders, gives the
log-odds that the number is printed with a minus: a tick or a blur beside the digits is its hardest
negative.

Its input is the left :data:`INPUT_WIDTH` columns of the number net's line input
(:func:`gauged.reader.ocr.number_net.to_line_input`: grey, 32 px tall, aspect kept, padded right).
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np

from gauged.reader.ocr.number_net import to_line_input
from gauged.reader.onnx_model import load_session

INPUT_WIDTH = 64  # columns: twice the line's height, the minus and the first digits


def minus_input(line_bgr: np.ndarray) -> np.ndarray:
    """(32, INPUT_WIDTH) uint8 grey: the left end of the number net's input of the line."""
    return np.ascontiguousarray(to_line_input(line_bgr)[:, :INPUT_WIDTH])


class MinusNet:
    """``log_odds(lines)`` -> for each (h, w, 3) uint8 BGR line, upright, the log-odds of a minus first."""

    def __init__(self, path: Path, threads: int = 2):
        self.path = path
        self.session, _ = load_session(path, threads, how_to_make="python -m gauged.training.minus_lines, docs/ocr.md")

    def log_odds(self, lines: Sequence[np.ndarray]) -> np.ndarray:
        if not lines:
            return np.zeros(0, np.float32)
        x = np.stack([minus_input(line) for line in lines])[:, None].astype(np.float32) * np.float32(1 / 255)
        return self.session.run(None, {"line": x})[0].reshape(-1)
