"""The number net at run time: onnxruntime reads scale-number lines (no torch).

The net is trained by :mod:`gauged.training.number_lines` on number lines of the engine's renders.
Given each held-out number at its true quad, it reads 85.9% of those captured 5-10 px tall, where
PP-OCR's recogniser reads 71.2% (docs/ocr.md, "A recogniser of our own"). The OCR engine
(:class:`gauged.reader.ocr.engine.OcrEngine`) gives it every line PP-OCR read digits in, and takes
its reading where it is a number.

A line is grey, resized to :data:`LINE_HEIGHT` px tall (aspect kept) and padded right with its
median to :data:`LINE_WIDTH` px; the output is (N, 32, len(CHARS) + 1) CTC logits, blank first.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import cv2
import numpy as np

from gauged.reader.ocr.text import ctc_log_likelihood
from gauged.reader.onnx_model import load_session

CHARS = "0123456789.,-"
LINE_HEIGHT, LINE_WIDTH = 32, 128
ODDS_FLOOR = 99.0  # the log-odds given when a string cannot be read from the columns at all


def to_line_input(line_bgr: np.ndarray) -> np.ndarray:
    """(LINE_HEIGHT, LINE_WIDTH) uint8 grey: the line resized to the height, padded right with its median."""
    grey = cv2.cvtColor(line_bgr, cv2.COLOR_BGR2GRAY)
    h, w = grey.shape
    width = max(1, min(LINE_WIDTH, int(round(w * LINE_HEIGHT / max(1, h)))))
    grey = cv2.resize(grey, (width, LINE_HEIGHT), interpolation=cv2.INTER_AREA if h > LINE_HEIGHT else cv2.INTER_CUBIC)
    out = np.full((LINE_HEIGHT, LINE_WIDTH), int(np.median(grey)), np.uint8)
    out[:, :width] = grey
    return out


def greedy_decode(logits: np.ndarray) -> list[str]:
    """Best path of (N, T, K) logits: repeats merged, blanks (class 0) dropped."""
    out = []
    for row in np.asarray(logits).argmax(-1):
        keep = (row != 0) & np.concatenate([[True], row[1:] != row[:-1]])
        out.append("".join(CHARS[k - 1] for k in row[keep]))
    return out


class NumberNet:
    """``read(lines)`` -> the net's string for each (h, w, 3) uint8 BGR line, upright."""

    def __init__(self, path: Path, threads: int = 2):
        self.path = path
        self.session, _ = load_session(path, threads, how_to_make="docs/ocr.md")

    def read(self, lines: Sequence[np.ndarray]) -> list[str]:
        return greedy_decode(self._logits(lines)) if lines else []

    def minus_log_odds(self, lines: Sequence[np.ndarray], digits: Sequence[str]) -> np.ndarray:
        """For each line, log P("-" + its digits) - log P(its digits) under the net's CTC columns: how
        much more the line reads as those digits after a minus than as the digits alone."""
        if not lines:
            return np.zeros(0)
        out = []
        for logits, text in zip(self._logits(lines), digits, strict=True):
            z = logits.astype(np.float64)
            top = z.max(axis=-1, keepdims=True)
            logp = z - top - np.log(np.exp(z - top).sum(axis=-1, keepdims=True))
            labels = [CHARS.index(c) + 1 for c in text if c in CHARS]
            odds = ctc_log_likelihood(logp, [CHARS.index("-") + 1, *labels]) - ctc_log_likelihood(logp, labels)
            out.append(odds if np.isfinite(odds) else -ODDS_FLOOR)
        return np.asarray(out)

    def _logits(self, lines: Sequence[np.ndarray]) -> np.ndarray:
        x = np.stack([to_line_input(line) for line in lines])[:, None].astype(np.float32) * np.float32(1 / 255)
        return self.session.run(None, {"line": x})[0]
